/* proto.h — codec of the client <-> manager protocol (docs/protocol.md): a growable writer,
 * a bounds-checked reader and the frame header rules, and (client_wire.h, generated at build
 * time from python/links_and_nodes/wire/client.schema) the protocol's constants, message
 * types and per-message write/read functions.  Pure functions: no I/O, no error text, so the
 * codec can be tested on byte strings alone. */
#ifndef LN_PROTO_H
#define LN_PROTO_H

#include <stddef.h>
#include <stdint.h>

#include "ln_internal.h"

/* Growable writer.  `failed` is 0, or the LN_E* code of the first failure: LN_ENOMEM, or
 * LN_EINVAL for a str that is NULL, longer than LN_PROTO_MAX_STR or not valid UTF-8.  After
 * a failure further writes are ignored, so a message is built unchecked and tested once.
 * The writer owns `data`; ln_wbuf_free releases it (and is safe on a zeroed wbuf). */
typedef struct ln_wbuf {
    uint8_t* data;
    size_t len;
    size_t cap;
    int failed;
} ln_wbuf;

void ln_wbuf_init(ln_wbuf* b);
void ln_wbuf_free(ln_wbuf* b);
void ln_wbuf_reset(ln_wbuf* b); /* len = 0, failed = 0, memory kept */
void ln_wbuf_u16(ln_wbuf* b, uint16_t v);
void ln_wbuf_u32(ln_wbuf* b, uint32_t v);
void ln_wbuf_u64(ln_wbuf* b, uint64_t v);
void ln_wbuf_i32(ln_wbuf* b, int32_t v);
void ln_wbuf_str(ln_wbuf* b, const char* s); /* u16 length + bytes, no NUL */
void ln_wbuf_bytes(ln_wbuf* b, const void* data, size_t n);
/* u32 length + bytes, no NUL: a `text` field (UTF-8, bounded by the frame size only);
 * LN_EINVAL for NULL or invalid UTF-8. */
void ln_wbuf_text(ln_wbuf* b, const char* s);

/* Bounds-checked reader over memory it does not own.  Reading past the end, or a str that is
 * too long for the caller, not UTF-8 or contains NUL, sets `failed` (LN_EPROTOCOL) and yields
 * 0 / ""; once failed, every further read yields 0 / "". */
typedef struct ln_rbuf {
    const uint8_t* p;
    size_t left;
    int failed;
} ln_rbuf;

/* A view of a str or text field: `len` bytes at `s`, not NUL-terminated.  Encoding reads
 * it (s NULL fails); decoding points it into the reader's memory, checked UTF-8 without NUL. */
typedef struct ln_strv {
    const char* s;
    size_t len;
} ln_strv;

/* The view of a C string (NULL stays NULL, so that encoding it fails). */
ln_strv ln_strv_of(const char* s);
/* Copies v NUL-terminated into out[size]: LN_OK, or LN_EPROTOCOL (out = "") if it does not
 * fit. */
int ln_strv_copy(ln_strv v, char* out, size_t size);

/* The generated part: constants LN_PROTO_*, enum ln_msg_type, ln_msg_* structs and
 * functions. */
#include "client_wire.h"

#define LN_PROTO_HEADER_SIZE (LN_PROTO_LENGTH_BYTES + LN_PROTO_TYPE_BYTES) /* length + type */

void ln_rbuf_init(ln_rbuf* r, const void* data, size_t len);
uint16_t ln_rbuf_u16(ln_rbuf* r);
uint32_t ln_rbuf_u32(ln_rbuf* r);
uint64_t ln_rbuf_u64(ln_rbuf* r);
int32_t ln_rbuf_i32(ln_rbuf* r);
/* Copies a str field NUL-terminated into out[outsize]; sets failed if it does not fit, is
 * longer than LN_PROTO_MAX_STR, is not valid UTF-8 or contains NUL. */
void ln_rbuf_str(ln_rbuf* r, char* out, size_t outsize);
/* A `text` field: points *len bytes into the reader's memory (not NUL-terminated); sets
 * failed if it is truncated, not UTF-8 or contains NUL.  NULL (and *len 0) on failure. */
const char* ln_rbuf_text(ln_rbuf* r, size_t* len);
/* View forms of str (at most `limit` bytes) and text fields, as the generated codec uses
 * them; the same checks as ln_wbuf_str/ln_wbuf_text and ln_rbuf_str/ln_rbuf_text. */
void ln_wbuf_strv(ln_wbuf* b, ln_strv v, size_t limit);
void ln_wbuf_textv(ln_wbuf* b, ln_strv v);
void ln_rbuf_strv(ln_rbuf* r, ln_strv* v, size_t limit);
void ln_rbuf_textv(ln_rbuf* r, ln_strv* v);
/* LN_OK if nothing failed and every byte was consumed, else LN_EPROTOCOL. */
int ln_rbuf_end(const ln_rbuf* r);

/* 1 if s[0..n) is valid UTF-8 (shortest form, no surrogates, <= U+10FFFF), else 0. */
int ln_utf8_valid(const char* s, size_t n);

/* Frames.  ln_proto_frame_begin appends a header with a placeholder length and returns where
 * the frame starts; the body follows with ln_wbuf_*; ln_proto_frame_end(b, start) fills in
 * the length and returns LN_OK, b->failed, or LN_ETOOBIG if the frame exceeds
 * LN_PROTO_MAX_FRAME. */
size_t ln_proto_frame_begin(ln_wbuf* b, uint16_t type);
int ln_proto_frame_end(ln_wbuf* b, size_t start);

/* Checks a received header: LN_OK with the body size and type, or LN_EPROTOCOL if `length`
 * is out of range or the type unknown. */
int ln_proto_parse_header(const uint8_t header[LN_PROTO_HEADER_SIZE], uint32_t* body_len,
                          uint16_t* type);

/* Checks that data[0..len) is exactly one frame: LN_OK with its type and a reader over its
 * body, else LN_EPROTOCOL (bad header, truncated, trailing bytes). */
int ln_proto_decode_frame(const void* data, size_t len, uint16_t* type, ln_rbuf* body);

/* 1 for the types of docs/protocol.md, else 0. */
int ln_proto_type_known(uint16_t type);
/* 1 for the types the manager sends (WELCOME, ERROR, PORT_OK, OK, TOPIC_INFO_OK,
 * SERVICE_INFO, CONTROL_RESULT), else 0. */
int ln_proto_to_client(uint16_t type);
/* LN_OK if `body` (from its start; the reader itself is not moved) holds exactly the fields of
 * message `type` with valid strs, else LN_EPROTOCOL.  A reader that passes can then be read
 * field by field without further checks. */
int ln_proto_check_fields(uint16_t type, const ln_rbuf* body);
/* The answer type that a request type succeeds with (PUBLISH -> PORT_OK, ...), or 0 if
 * `type` is not a request that carries a request id. */
uint16_t ln_proto_answer_type(uint16_t request_type);
/* "PUBLISH" etc. for error texts; "UNKNOWN" for a type not in the protocol. */
const char* ln_proto_type_name(uint16_t type);

#endif /* LN_PROTO_H */
