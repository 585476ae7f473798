/* proto.c — byte-level codec of the manager protocol: little-endian integers, length-prefixed
 * UTF-8 strings and frame headers, with every bound of docs/protocol.md checked here so the
 * callers only see well-formed values or a failure flag. */
#include "proto.h"

#include <assert.h>
#include <stdlib.h>
#include <string.h>

/* ---- writer -------------------------------------------------------------------------- */

void ln_wbuf_init(ln_wbuf* b)
{
    b->data = NULL;
    b->len = 0;
    b->cap = 0;
    b->failed = 0;
}

void ln_wbuf_free(ln_wbuf* b)
{
    free(b->data);
    ln_wbuf_init(b);
}

void ln_wbuf_reset(ln_wbuf* b)
{
    b->len = 0;
    b->failed = 0;
}

/* Room for n more bytes; returns a pointer to them or NULL (failed set). */
static uint8_t* wbuf_grow(ln_wbuf* b, size_t n)
{
    if (b->failed)
        return NULL;
    if (n > SIZE_MAX / 2 - b->len) {
        b->failed = LN_ENOMEM;
        return NULL;
    }
    if (b->len + n > b->cap || b->data == NULL) { /* never NULL + 0, even for n == 0 */
        size_t cap = b->cap ? b->cap : 64;
        while (cap < b->len + n)
            cap *= 2;
        uint8_t* data = realloc(b->data, cap);
        if (data == NULL) {
            b->failed = LN_ENOMEM;
            return NULL;
        }
        b->data = data;
        b->cap = cap;
    }
    uint8_t* at = b->data + b->len;
    b->len += n;
    return at;
}

static void put_le(uint8_t* at, uint64_t v, size_t n)
{
    for (size_t i = 0; i < n; i++)
        at[i] = (uint8_t)(v >> (8 * i));
}

static void wbuf_le(ln_wbuf* b, uint64_t v, size_t n)
{
    uint8_t* at = wbuf_grow(b, n);
    if (at != NULL)
        put_le(at, v, n);
}

void ln_wbuf_u16(ln_wbuf* b, uint16_t v) { wbuf_le(b, v, 2); }
void ln_wbuf_u32(ln_wbuf* b, uint32_t v) { wbuf_le(b, v, 4); }
void ln_wbuf_u64(ln_wbuf* b, uint64_t v) { wbuf_le(b, v, 8); }
void ln_wbuf_i32(ln_wbuf* b, int32_t v) { wbuf_le(b, (uint32_t)v, 4); }

void ln_wbuf_bytes(ln_wbuf* b, const void* data, size_t n)
{
    uint8_t* at = wbuf_grow(b, n);
    if (at != NULL && n > 0)
        memcpy(at, data, n);
}

ln_strv ln_strv_of(const char* s)
{
    ln_strv v = {s, s != NULL ? strlen(s) : 0};
    return v;
}

int ln_strv_copy(ln_strv v, char* out, size_t size)
{
    assert(out != NULL && size > 0);
    out[0] = '\0';
    if (v.len >= size)
        return LN_EPROTOCOL;
    if (v.len > 0)
        memcpy(out, v.s, v.len);
    out[v.len] = '\0';
    return LN_OK;
}

void ln_wbuf_strv(ln_wbuf* b, ln_strv v, size_t limit)
{
    if (b->failed)
        return;
    if (v.s == NULL || v.len > limit || v.len > UINT16_MAX || !ln_utf8_valid(v.s, v.len)) {
        b->failed = LN_EINVAL;
        return;
    }
    ln_wbuf_u16(b, (uint16_t)v.len);
    ln_wbuf_bytes(b, v.s, v.len);
}

void ln_wbuf_str(ln_wbuf* b, const char* s)
{
    ln_strv v = {s, s != NULL ? strnlen(s, LN_PROTO_MAX_STR + 1) : 0};
    ln_wbuf_strv(b, v, LN_PROTO_MAX_STR);
}

void ln_wbuf_textv(ln_wbuf* b, ln_strv v)
{
    if (b->failed)
        return;
    if (v.s == NULL || v.len > UINT32_MAX || !ln_utf8_valid(v.s, v.len)) {
        b->failed = LN_EINVAL;
        return;
    }
    ln_wbuf_u32(b, (uint32_t)v.len);
    ln_wbuf_bytes(b, v.s, v.len);
}

void ln_wbuf_text(ln_wbuf* b, const char* s) { ln_wbuf_textv(b, ln_strv_of(s)); }

/* ---- reader -------------------------------------------------------------------------- */

void ln_rbuf_init(ln_rbuf* r, const void* data, size_t len)
{
    r->p = data;
    r->left = len;
    r->failed = 0;
}

/* The next n bytes, or NULL (failed set) if there are fewer. */
static const uint8_t* rbuf_take(ln_rbuf* r, size_t n)
{
    if (r->failed || r->left < n) {
        r->failed = LN_EPROTOCOL;
        return NULL;
    }
    const uint8_t* at = r->p;
    r->p += n;
    r->left -= n;
    return at;
}

static uint64_t rbuf_le(ln_rbuf* r, size_t n)
{
    const uint8_t* at = rbuf_take(r, n);
    uint64_t v = 0;
    for (size_t i = 0; at != NULL && i < n; i++)
        v |= (uint64_t)at[i] << (8 * i);
    return v;
}

uint16_t ln_rbuf_u16(ln_rbuf* r) { return (uint16_t)rbuf_le(r, 2); }
uint32_t ln_rbuf_u32(ln_rbuf* r) { return (uint32_t)rbuf_le(r, 4); }
uint64_t ln_rbuf_u64(ln_rbuf* r) { return rbuf_le(r, 8); }
int32_t ln_rbuf_i32(ln_rbuf* r) { return (int32_t)(uint32_t)rbuf_le(r, 4); }

void ln_rbuf_strv(ln_rbuf* r, ln_strv* v, size_t limit)
{
    v->s = "";
    v->len = 0;
    size_t n = ln_rbuf_u16(r);
    const char* s = (const char*)rbuf_take(r, n);
    if (s == NULL)
        return;
    if (n > limit || memchr(s, '\0', n) != NULL || !ln_utf8_valid(s, n)) {
        r->failed = LN_EPROTOCOL;
        return;
    }
    v->s = s;
    v->len = n;
}

void ln_rbuf_str(ln_rbuf* r, char* out, size_t outsize)
{
    assert(out != NULL && outsize > 0);
    ln_strv v;
    ln_rbuf_strv(r, &v, LN_PROTO_MAX_STR);
    if (ln_strv_copy(v, out, outsize) != LN_OK)
        r->failed = LN_EPROTOCOL;
}

void ln_rbuf_textv(ln_rbuf* r, ln_strv* v)
{
    v->s = "";
    v->len = 0;
    size_t n = ln_rbuf_u32(r);
    const char* s = (const char*)rbuf_take(r, n);
    if (s == NULL)
        return;
    if (memchr(s, '\0', n) != NULL || !ln_utf8_valid(s, n)) {
        r->failed = LN_EPROTOCOL;
        return;
    }
    v->s = s;
    v->len = n;
}

const char* ln_rbuf_text(ln_rbuf* r, size_t* len)
{
    ln_strv v;
    ln_rbuf_textv(r, &v);
    *len = r->failed ? 0 : v.len;
    return r->failed ? NULL : v.s;
}

int ln_rbuf_end(const ln_rbuf* r) { return r->failed || r->left != 0 ? LN_EPROTOCOL : LN_OK; }

/* ---- UTF-8 ----------------------------------------------------------------------------
 * Strict RFC 3629: the same set of byte strings Python's str.decode('utf-8') accepts, so
 * the manager and the library agree on what is malformed. */
int ln_utf8_valid(const char* s, size_t n)
{
    const uint8_t* p = (const uint8_t*)s;
    size_t i = 0;
    while (i < n) {
        uint8_t c = p[i];
        size_t more;
        uint8_t lo = 0x80, hi = 0xBF; /* allowed range of the first continuation byte */
        if (c < 0x80) {
            i++;
            continue;
        } else if (c >= 0xC2 && c <= 0xDF) {
            more = 1;
        } else if (c >= 0xE0 && c <= 0xEF) {
            more = 2;
            if (c == 0xE0)
                lo = 0xA0; /* no overlong 3-byte forms */
            else if (c == 0xED)
                hi = 0x9F; /* no UTF-16 surrogates */
        } else if (c >= 0xF0 && c <= 0xF4) {
            more = 3;
            if (c == 0xF0)
                lo = 0x90; /* no overlong 4-byte forms */
            else if (c == 0xF4)
                hi = 0x8F; /* nothing above U+10FFFF */
        } else {
            return 0; /* continuation byte, overlong C0/C1 lead or F5..FF */
        }
        if (n - i - 1 < more)
            return 0;
        if (p[i + 1] < lo || p[i + 1] > hi)
            return 0;
        for (size_t k = 2; k <= more; k++)
            if ((p[i + k] & 0xC0) != 0x80)
                return 0;
        i += more + 1;
    }
    return 1;
}

/* ---- frames -------------------------------------------------------------------------- */

size_t ln_proto_frame_begin(ln_wbuf* b, uint16_t type)
{
    size_t start = b->len;
    ln_wbuf_u32(b, 0); /* filled in by ln_proto_frame_end */
    ln_wbuf_u16(b, type);
    return start;
}

int ln_proto_frame_end(ln_wbuf* b, size_t start)
{
    if (b->failed)
        return b->failed;
    assert(start + LN_PROTO_HEADER_SIZE <= b->len);
    size_t length = b->len - start - LN_PROTO_LENGTH_BYTES;
    if (length > LN_PROTO_MAX_FRAME)
        return LN_ETOOBIG;
    put_le(b->data + start, length, LN_PROTO_LENGTH_BYTES);
    return LN_OK;
}

int ln_proto_parse_header(const uint8_t header[LN_PROTO_HEADER_SIZE], uint32_t* body_len,
                          uint16_t* type)
{
    ln_rbuf r;
    ln_rbuf_init(&r, header, LN_PROTO_HEADER_SIZE);
    uint32_t length = ln_rbuf_u32(&r);
    uint16_t t = ln_rbuf_u16(&r);
    if (length < LN_PROTO_MIN_FRAME || length > LN_PROTO_MAX_FRAME || !ln_proto_type_known(t))
        return LN_EPROTOCOL;
    *body_len = length - LN_PROTO_TYPE_BYTES;
    *type = t;
    return LN_OK;
}

int ln_proto_decode_frame(const void* data, size_t len, uint16_t* type, ln_rbuf* body)
{
    uint32_t body_len;
    if (len < LN_PROTO_HEADER_SIZE || ln_proto_parse_header(data, &body_len, type) != LN_OK ||
        len - LN_PROTO_HEADER_SIZE != body_len)
        return LN_EPROTOCOL;
    ln_rbuf_init(body, (const uint8_t*)data + LN_PROTO_HEADER_SIZE, body_len);
    return LN_OK;
}

/* ---- message types ---------------------------------------------------------------------
 * The table and the field checks are generated from the schema (client_wire.c). */

/* The flag bits the schema gives the wire are ln.h's option bits. */
_Static_assert(LN_PROTO_PUBLISH_WAIT_FOR_SUBSCRIBERS == LN_PUBLISH_WAIT_FOR_SUBSCRIBERS,
               "client.schema and ln.h disagree on PUBLISH_WAIT_FOR_SUBSCRIBERS");
_Static_assert(LN_PROTO_SUBSCRIBE_UDP == LN_SUBSCRIBE_UDP, "client.schema and ln.h disagree");
_Static_assert(LN_PROTO_SUBSCRIBE_TCP == LN_SUBSCRIBE_TCP, "client.schema and ln.h disagree");

static const ln_wire_msg_info* find_type(uint16_t type)
{
    for (size_t i = 0; i < ln_client_wire_msg_count; i++)
        if (ln_client_wire_msgs[i].type == type)
            return &ln_client_wire_msgs[i];
    return NULL;
}

int ln_proto_type_known(uint16_t type) { return find_type(type) != NULL; }

int ln_proto_to_client(uint16_t type)
{
    const ln_wire_msg_info* m = find_type(type);
    return m != NULL && m->to_client;
}

uint16_t ln_proto_answer_type(uint16_t request_type)
{
    const ln_wire_msg_info* m = find_type(request_type);
    return m != NULL ? m->answer : 0;
}

const char* ln_proto_type_name(uint16_t type)
{
    const ln_wire_msg_info* m = find_type(type);
    return m != NULL ? m->name : "UNKNOWN";
}

int ln_proto_check_fields(uint16_t type, const ln_rbuf* body)
{
    return ln_client_wire_check(type, body);
}
