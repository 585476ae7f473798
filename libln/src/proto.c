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
    if (b->len + n > b->cap) {
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

void ln_wbuf_str(ln_wbuf* b, const char* s)
{
    if (b->failed)
        return;
    size_t n = s != NULL ? strnlen(s, LN_PROTO_MAX_STR + 1) : 0;
    if (s == NULL || n > LN_PROTO_MAX_STR || !ln_utf8_valid(s, n)) {
        b->failed = LN_EINVAL;
        return;
    }
    ln_wbuf_u16(b, (uint16_t)n);
    ln_wbuf_bytes(b, s, n);
}

void ln_wbuf_text(ln_wbuf* b, const char* s)
{
    if (b->failed)
        return;
    size_t n = s != NULL ? strlen(s) : 0;
    if (s == NULL || n > UINT32_MAX || !ln_utf8_valid(s, n)) {
        b->failed = LN_EINVAL;
        return;
    }
    ln_wbuf_u32(b, (uint32_t)n);
    ln_wbuf_bytes(b, s, n);
}

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

void ln_rbuf_str(ln_rbuf* r, char* out, size_t outsize)
{
    assert(out != NULL && outsize > 0);
    out[0] = '\0';
    size_t n = ln_rbuf_u16(r);
    const char* s = (const char*)rbuf_take(r, n);
    if (s == NULL)
        return;
    if (n > LN_PROTO_MAX_STR || n >= outsize || memchr(s, '\0', n) != NULL
        || !ln_utf8_valid(s, n)) {
        r->failed = LN_EPROTOCOL;
        return;
    }
    memcpy(out, s, n);
    out[n] = '\0';
}

const char* ln_rbuf_text(ln_rbuf* r, size_t* len)
{
    *len = 0;
    size_t n = ln_rbuf_u32(r);
    const char* s = (const char*)rbuf_take(r, n);
    if (s == NULL)
        return NULL;
    if (memchr(s, '\0', n) != NULL || !ln_utf8_valid(s, n)) {
        r->failed = LN_EPROTOCOL;
        return NULL;
    }
    *len = n;
    return s;
}

int ln_rbuf_end(const ln_rbuf* r)
{
    return r->failed || r->left != 0 ? LN_EPROTOCOL : LN_OK;
}

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
    size_t length = b->len - start - 4;
    if (length > LN_PROTO_MAX_FRAME)
        return LN_ETOOBIG;
    put_le(b->data + start, length, 4);
    return LN_OK;
}

int ln_proto_parse_header(const uint8_t header[LN_PROTO_HEADER_SIZE], uint32_t* body_len,
                          uint16_t* type)
{
    ln_rbuf r;
    ln_rbuf_init(&r, header, LN_PROTO_HEADER_SIZE);
    uint32_t length = ln_rbuf_u32(&r);
    uint16_t t = ln_rbuf_u16(&r);
    if (length < 2 || length > LN_PROTO_MAX_FRAME || !ln_proto_type_known(t))
        return LN_EPROTOCOL;
    *body_len = length - 2;
    *type = t;
    return LN_OK;
}

int ln_proto_decode_frame(const void* data, size_t len, uint16_t* type, ln_rbuf* body)
{
    uint32_t body_len;
    if (len < LN_PROTO_HEADER_SIZE || ln_proto_parse_header(data, &body_len, type) != LN_OK
        || len - LN_PROTO_HEADER_SIZE != body_len)
        return LN_EPROTOCOL;
    ln_rbuf_init(body, (const uint8_t*)data + LN_PROTO_HEADER_SIZE, body_len);
    return LN_OK;
}

/* ---- message types ------------------------------------------------------------------- */

/* Every message's fields in order, one letter each: w u16, d u32, q u64, i i32, s str, t text.  The
 * request id is the leading `d` of the types that carry one. */
static const struct {
    uint16_t type;
    uint16_t answer; /* for requests with a request id: the type of a successful answer */
    int to_client;   /* sent by the manager */
    const char* fields;
    const char* name;
} msg_types[] = {
    {LN_MSG_HELLO, 0, 0, "dwdsssd", "HELLO"},
    {LN_MSG_WELCOME, 0, 1, "wdss", "WELCOME"},
    {LN_MSG_ERROR, 0, 1, "dis", "ERROR"},
    {LN_MSG_PUBLISH, LN_MSG_PORT_OK, 0, "dssqddd", "PUBLISH"},
    {LN_MSG_SUBSCRIBE, LN_MSG_PORT_OK, 0, "dssqddd", "SUBSCRIBE"},
    {LN_MSG_PORT_OK, 0, 1, "ddsd", "PORT_OK"},
    {LN_MSG_CLOSE_PORT, LN_MSG_OK, 0, "dd", "CLOSE_PORT"},
    {LN_MSG_OK, 0, 1, "d", "OK"},
    {LN_MSG_TOPIC_INFO, LN_MSG_TOPIC_INFO_OK, 0, "ds", "TOPIC_INFO"},
    {LN_MSG_TOPIC_INFO_OK, 0, 1, "dsqddd", "TOPIC_INFO_OK"},
    {LN_MSG_RECLAIM_PORT, LN_MSG_PORT_OK, 0, "dwssqdddsd", "RECLAIM_PORT"},
    {LN_MSG_REGISTER_SERVICE, LN_MSG_OK, 0, "dssqsssssw", "REGISTER_SERVICE"},
    {LN_MSG_UNREGISTER_SERVICE, LN_MSG_OK, 0, "ds", "UNREGISTER_SERVICE"},
    {LN_MSG_FIND_SERVICE, LN_MSG_SERVICE_INFO, 0, "dssq", "FIND_SERVICE"},
    {LN_MSG_SERVICE_INFO, 0, 1, "dssssws", "SERVICE_INFO"},
    {LN_MSG_SERVICE_CALLED, LN_MSG_OK, 0, "dsqq", "SERVICE_CALLED"},
    {LN_MSG_CONTROL, LN_MSG_CONTROL_RESULT, 0, "dt", "CONTROL"},
    {LN_MSG_CONTROL_RESULT, 0, 1, "dt", "CONTROL_RESULT"},
};

static int find_type(uint16_t type)
{
    for (size_t i = 0; i < LN_ARRAY_SIZE(msg_types); i++)
        if (msg_types[i].type == type)
            return (int)i;
    return -1;
}

int ln_proto_type_known(uint16_t type)
{
    return find_type(type) >= 0;
}

int ln_proto_to_client(uint16_t type)
{
    int i = find_type(type);
    return i >= 0 && msg_types[i].to_client;
}

uint16_t ln_proto_answer_type(uint16_t request_type)
{
    int i = find_type(request_type);
    return i >= 0 ? msg_types[i].answer : 0;
}

const char* ln_proto_type_name(uint16_t type)
{
    int i = find_type(type);
    return i >= 0 ? msg_types[i].name : "UNKNOWN";
}

int ln_proto_check_fields(uint16_t type, const ln_rbuf* body)
{
    int i = find_type(type);
    if (i < 0)
        return LN_EPROTOCOL;
    ln_rbuf r = *body;
    char text[LN_PROTO_MAX_STR + 1];
    for (const char* f = msg_types[i].fields; *f != '\0'; f++) {
        switch (*f) {
        case 'w': ln_rbuf_u16(&r); break;
        case 'd': ln_rbuf_u32(&r); break;
        case 'q': ln_rbuf_u64(&r); break;
        case 'i': ln_rbuf_i32(&r); break;
        case 't': {
            size_t n;
            ln_rbuf_text(&r, &n);
            break;
        }
        default: ln_rbuf_str(&r, text, sizeof text); break;
        }
    }
    return ln_rbuf_end(&r);
}
