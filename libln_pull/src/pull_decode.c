/* pull_decode.c — the consumer's view of a received packet (pull_internal.h).  The full build
 * takes it from the generic codec (ln_ndn_decode, ln_ndn_decode_pull_content); a device's
 * consumer-only build (-DLN_NDN_CONSUMER) has a compact decoder here instead: the same
 * packets accepted with the same error codes (tests/fuzz/fuzz_pull_device.c checks it
 * against the generic one), the grammars as a table walked by one loop (no callbacks, no
 * recursion, so its stack is bounded statically), 32-bit arithmetic where the wire allows
 * it, and none of the C library's functions. */
#include <string.h>

#include "pull_internal.h"

#ifndef LN_NDN_CONSUMER
int ln_ndn_i_decode_reply(const uint8_t* buf, size_t size, ln_ndn_i_reply* out)
{
    ln_ndn_packet p; /* in this frame only: the consumer's own frame stays small */
    int r = ln_ndn_decode(buf, size, &p);
    memset(out, 0, sizeof *out);
    if (r < 0)
        return r;
    out->type = (uint8_t)p.type;
    if (p.type == LN_NDN_T_INTEREST) {
        out->name = p.interest.name;
        out->nonce = p.interest.nonce;
        out->has_nonce = p.interest.has_nonce;
        out->lp_nack = p.lp_nack;
    } else {
        out->name = p.data.name;
        out->content = p.data.content;
        out->signed_portion = p.data.signed_portion;
        out->signature = p.data.signature_value;
        out->content_type = p.data.content_type;
        out->signature_type = p.data.signature_type;
    }
    return LN_NDN_OK;
}

int ln_ndn_i_decode_content(const ln_ndn_bytes* content, ln_ndn_pull_content* out)
{
    return ln_ndn_decode_pull_content(*content, out);
}

int ln_ndn_i_component(ln_ndn_bytes* rest, ln_ndn_component* out)
{
    return ln_ndn_name_next(rest, out);
}

int ln_ndn_i_nonneg(const ln_ndn_bytes* value, uint64_t* out)
{
    return ln_ndn_read_nonneg(*value, out);
}

#else /* LN_NDN_CONSUMER */

#if defined(__GNUC__) && !defined(__clang__)
/* keep these loops loops: GCC would turn them into calls of memset/memcpy/memcmp */
#define PLAIN_LOOP __attribute__((optimize("no-tree-loop-distribute-patterns")))
#else
#define PLAIN_LOOP
#endif

PLAIN_LOOP void ln_ndn_i_zero(void* p, size_t n)
{
    uint8_t* b = p;
    while (n--)
        *b++ = 0;
}

PLAIN_LOOP void ln_ndn_i_copy(void* to, const void* from, size_t n)
{
    uint8_t* t = to;
    const uint8_t* f = from;
    while (n--)
        *t++ = *f++;
}

PLAIN_LOOP int ln_ndn_i_differ(const void* a, const void* b, size_t n)
{
    const uint8_t *x = a, *y = b;
    uint8_t d = 0;
    while (n--)
        d |= *x++ ^ *y++; /* in constant time: it compares signatures too */
    return d;
}

/* One TLV off the front of *rest: 1, 0 at the end, or LN_NDN_ETRUNCATED.  A type above
 * 2^32 - 1 comes out as 0xfffffffe or 0xffffffff: no known type, and critical exactly when the
 * real one is (odd); a length above it is truncated (buffers are below 4 GiB). */
static int tlv(ln_ndn_bytes* rest, uint32_t* type, ln_ndn_bytes* value)
{
    const uint8_t *p = rest->data, *end;
    uint32_t n, x = 0, big;
    int k;
    if (!rest->size) /* first: an absent value's data may be NULL */
        return 0;
    end = p + rest->size;
    for (k = 0; k < 2; k++) { /* VAR-NUMBERs: the type, then the length */
        if (p == end)
            return LN_NDN_ETRUNCATED;
        x = *p++;
        if (x >= 253) { /* 2, 4 or 8 bytes follow */
            n = 2u << (x - 253);
            if (n > (size_t)(end - p))
                return LN_NDN_ETRUNCATED;
            for (big = x = 0; n; n--) {
                big |= x >> 24;
                x = x << 8 | *p++;
            }
            if (big) /* the type: 0xfffffffe | its low bit; the length: 0xffffffff */
                x |= 0xfffffffeu | (uint32_t)k;
        }
        if (!k)
            *type = x;
    }
    if (x > (size_t)(end - p))
        return LN_NDN_ETRUNCATED;
    value->data = p;
    value->size = x;
    rest->data = p + x;
    rest->size = (size_t)(end - p) - x;
    return 1;
}

/* *to = from, field by field: GCC -Os copies an ln_ndn_bytes with memcpy on a Cortex-M0 */
#define SET(to, from) ((to).data = (from).data, (to).size = (from).size)

/* Only a verifying consumer (-DLN_PULL_HMAC) reads the signed portion, SignatureType and
 * SignatureValue: without it they are checked as ln_ndn_decode checks them, not kept. */
#ifdef LN_PULL_HMAC
#define KEEP_SIGNATURE 1
#else
#define KEEP_SIGNATURE 0
#endif

/* The evolvability rule of packet format 0.3 */
static int critical(uint32_t type) { return type < 32 || (type & 1u); }

int ln_ndn_i_component(ln_ndn_bytes* rest, ln_ndn_component* out)
{
    int r = tlv(rest, &out->type, &out->value);
    if (r > 0 && (out->type == 0 || out->type > 0xffffu))
        return LN_NDN_EMALFORMED;
    return r;
}

int ln_ndn_i_nonneg(const ln_ndn_bytes* value, uint64_t* out)
{
    uint64_t v = 0;
    size_t i, n = value->size;
    if (n != 1 && n != 2 && n != 4 && n != 8)
        return LN_NDN_EMALFORMED;
    for (i = 0; i < n; i++)
        v = v << 8 | value->data[i];
    *out = v;
    return LN_NDN_OK;
}

/* A name value of at least `min` components. */
static int check_name(const ln_ndn_bytes* value, int min)
{
    ln_ndn_component c;
    ln_ndn_bytes name;
    int r;
    SET(name, *value);
    while ((r = ln_ndn_i_component(&name, &c)) > 0)
        min--;
    return r < 0 ? r : min > 0 ? LN_NDN_EMALFORMED : LN_NDN_OK;
}

/* The grammars: for each, its elements in order as {type, what to do with it}.  Each known
 * element must come after the previous known one, else it counts as unknown; unknown ones
 * follow the evolvability rule (ln_ndn_decode's walk). */
enum {
    OP_SKIP,
    OP_NAME0, /* a name (Data's: may be empty; the signed portion starts here) */
    OP_NAME1, /* a name of at least one component (an Interest's) */
    OP_NONCE,
    OP_EMPTY,  /* CanBePrefix, MustBeFresh */
    OP_NONNEG, /* InterestLifetime, FreshnessPeriod: checked only */
    OP_BYTE,   /* HopLimit */
    OP_CONTENT_TYPE,
    OP_SIG_TYPE,
    OP_FINAL_BLOCK, /* exactly one name component */
    OP_META,        /* MetaInfo: its elements (grammar G_META) */
    OP_SIG_INFO,    /* SignatureInfo: its elements (G_SIG_INFO), then the signed portion */
    OP_CONTENT,
    OP_SIG_VALUE,
    OP_NUMBER, /* a pull-content header: latest, publish time, period (by index) */
    OP_PAYLOAD,
};
enum { G_INTEREST = 0, G_DATA = 10, G_META = 15, G_SIG_INFO = 18, G_CONTENT = 20, G_END = 24 };
static const uint8_t rules[G_END][2] = {
    /* G_INTEREST */
    {LN_NDN_T_NAME, OP_NAME1},
    {LN_NDN_T_CAN_BE_PREFIX, OP_EMPTY},
    {LN_NDN_T_MUST_BE_FRESH, OP_EMPTY},
    {LN_NDN_T_FORWARDING_HINT, OP_SKIP},
    {LN_NDN_T_NONCE, OP_NONCE},
    {LN_NDN_T_INTEREST_LIFETIME, OP_NONNEG},
    {LN_NDN_T_HOP_LIMIT, OP_BYTE},
    {LN_NDN_T_APP_PARAMETERS, OP_SKIP},
    {0x2c /* InterestSignatureInfo */, OP_SKIP},
    {0x2e /* InterestSignatureValue */, OP_SKIP},
    /* G_DATA */
    {LN_NDN_T_NAME, OP_NAME0},
    {LN_NDN_T_META_INFO, OP_META},
    {LN_NDN_T_CONTENT, OP_CONTENT},
    {LN_NDN_T_SIGNATURE_INFO, OP_SIG_INFO},
    {LN_NDN_T_SIGNATURE_VALUE, OP_SIG_VALUE},
    /* G_META */
    {LN_NDN_T_CONTENT_TYPE, OP_CONTENT_TYPE},
    {LN_NDN_T_FRESHNESS_PERIOD, OP_NONNEG},
    {LN_NDN_T_FINAL_BLOCK_ID, OP_FINAL_BLOCK},
    /* G_SIG_INFO */
    {LN_NDN_T_SIGNATURE_TYPE, OP_SIG_TYPE},
    {LN_NDN_T_KEY_LOCATOR, OP_SKIP},
    /* G_CONTENT */
    {LN_NDN_T_PULL_LATEST, OP_NUMBER},
    {LN_NDN_T_PULL_TIME, OP_NUMBER},
    {LN_NDN_T_PULL_PERIOD, OP_NUMBER},
    {LN_NDN_T_PULL_PAYLOAD, OP_PAYLOAD},
};

/* OP_NUMBER stores the i-th header at byte 8·i of ln_ndn_pull_content (C99: no static_assert) */
typedef char ln_ndn_i_numbers_in_order[offsetof(ln_ndn_pull_content, publish_us) == 8 &&
                                               offsetof(ln_ndn_pull_content, period_us) == 16
                                           ? 1
                                           : -1];

/* Where a walk puts what it finds */
typedef struct found {
    ln_ndn_i_reply* reply;        /* G_INTEREST, G_DATA */
    ln_ndn_pull_content* content; /* G_CONTENT */
    const uint8_t* name_start;    /* Data: the Name element's first byte */
    const uint8_t* sig_info_end;
    uint8_t deep; /* MetaInfo and SignatureInfo would nest beyond LN_NDN_MAX_DEPTH */
    uint8_t has_sig_type, has_sig_info, has_sig_value;
} found;

/* One nesting level of a walk: the rest of its value, its grammar (first rule, end) */
typedef struct level {
    ln_ndn_bytes rest;
    uint8_t rule, end, op; /* op: the element that opened it */
} level;

/* Walks `value` by the grammar starting at rules[g] up to rules[end], and the MetaInfo and
 * SignatureInfo inside it, in one loop (no recursion: the stack stays bounded). */
static int walk(const ln_ndn_bytes* value, uint8_t g, uint8_t end, found* x)
{
    level lv[2], *l = lv;
    ln_ndn_bytes f;
    ln_ndn_component c;
    const uint8_t* start;
    uint32_t type;
    uint64_t v;
    uint8_t i;
    int r;
    SET(l->rest, *value);
    l->rule = g;
    l->end = end;
    for (;;) {
        start = l->rest.data;
        if ((r = tlv(&l->rest, &type, &f)) < 0)
            return r;
        if (!r) {
            if (l == lv)
                return LN_NDN_OK;
            if (l->op == OP_SIG_INFO) {
                if (!x->has_sig_type || !x->name_start)
                    return LN_NDN_EMALFORMED;
                x->has_sig_info = 1;
                if (KEEP_SIGNATURE) {
                    x->reply->signed_portion.data = x->name_start;
                    x->reply->signed_portion.size = (size_t)(x->sig_info_end - x->name_start);
                }
            }
            l = lv;
            continue;
        }
        for (i = l->rule; i < l->end && rules[i][0] != type; i++) {
        }
        if (i == l->end) {
            if (critical(type))
                return LN_NDN_ECRITICAL;
            continue;
        }
        l->rule = (uint8_t)(i + 1);
        switch (rules[i][1]) {
        case OP_NAME0:
        case OP_NAME1:
            if ((r = check_name(&f, rules[i][1] == OP_NAME1)) < 0)
                return r;
            SET(x->reply->name, f);
            x->name_start = start;
            break;
        case OP_NONCE:
            if (f.size != 4)
                return LN_NDN_EMALFORMED;
            x->reply->nonce = (uint32_t)f.data[0] << 24 | (uint32_t)f.data[1] << 16 |
                              (uint32_t)f.data[2] << 8 | f.data[3];
            x->reply->has_nonce = 1;
            break;
        case OP_EMPTY:
            if (f.size)
                return LN_NDN_EMALFORMED;
            break;
        case OP_BYTE:
            if (f.size != 1)
                return LN_NDN_EMALFORMED;
            break;
        case OP_NONNEG:
        case OP_CONTENT_TYPE:
        case OP_SIG_TYPE:
        case OP_NUMBER:
            if ((r = ln_ndn_i_nonneg(&f, &v)) < 0)
                return r;
            if (v > 0xffffffffu && rules[i][1] != OP_NUMBER)
                v = 0xffffffffu;
            if (rules[i][1] == OP_CONTENT_TYPE)
                x->reply->content_type = (uint32_t)v;
            if (rules[i][1] == OP_SIG_TYPE) {
                if (KEEP_SIGNATURE)
                    x->reply->signature_type = (uint32_t)v;
                x->has_sig_type = 1;
            }
            if (rules[i][1] == OP_NUMBER)
                /* latest_seq, publish_us, period_us: 8 bytes apart, in the rules' order */
                *(uint64_t*)((uint8_t*)x->content + 8 * (i - G_CONTENT)) = v;
            break;
        case OP_FINAL_BLOCK:
            if ((r = ln_ndn_i_component(&f, &c)) < 0)
                return r;
            if (r != 1 || f.size)
                return LN_NDN_EMALFORMED;
            break;
        case OP_META:
        case OP_SIG_INFO:
            if (x->deep)
                return LN_NDN_EDEPTH;
            l = lv + 1;
            SET(l->rest, f);
            l->op = rules[i][1];
            /* OP_META: G_META..G_SIG_INFO; OP_SIG_INFO (its successor): G_SIG_INFO..G_CONTENT */
            l->rule = (uint8_t)(G_META + 3 * (l->op - OP_META));
            l->end = (uint8_t)(G_SIG_INFO + 2 * (l->op - OP_META));
            x->sig_info_end = f.data + f.size;
            break;
        case OP_CONTENT:
            SET(x->reply->content, f);
            break;
        case OP_SIG_VALUE:
            if (KEEP_SIGNATURE)
                SET(x->reply->signature, f);
            x->has_sig_value = 1;
            break;
        case OP_PAYLOAD:
            SET(x->content->payload, f);
            break;
        default: /* OP_SKIP */
            break;
        }
    }
}

/* The headers of one LpPacket; its fragment into *fragment.  LN_NDN_OK, or an error. */
static int lp_headers(const ln_ndn_bytes* packet, ln_ndn_bytes* fragment, int* nack)
{
    ln_ndn_bytes value, f, g;
    uint32_t type;
    uint64_t v;
    int r;
    SET(value, *packet);
    fragment->data = NULL;
    fragment->size = 0;
    while ((r = tlv(&value, &type, &f)) > 0) {
        if (fragment->data) /* nothing may follow the fragment */
            return LN_NDN_EMALFORMED;
        if (type == LN_NDN_T_LP_FRAGMENT) {
            if (!f.size)
                return LN_NDN_EMALFORMED;
            SET(*fragment, f);
        } else if (type == LN_NDN_T_LP_PIT_TOKEN) {
            if (f.size < 1 || f.size > 32)
                return LN_NDN_EMALFORMED;
        } else if (type == LN_NDN_T_LP_NACK) {
            *nack = 1;
            while ((r = tlv(&f, &type, &g)) > 0) {
                if (type == LN_NDN_T_LP_NACK_REASON) {
                    if ((r = ln_ndn_i_nonneg(&g, &v)) < 0)
                        return r;
                } else if (critical(type)) {
                    return LN_NDN_ECRITICAL;
                }
            }
            if (r < 0)
                return r;
        } else if (type == 0x52 || type == 0x53) { /* FragIndex 0, FragCount 1 only */
            if ((r = ln_ndn_i_nonneg(&f, &v)) < 0)
                return r;
            if (v != (type == 0x53))
                return LN_NDN_EUNSUPPORTED;
        } else if (type != 0x51 && /* Sequence; else only ignorable LP headers */
                   !(type >= 800 && type <= 959 && (type & 3u) == 0)) {
            return LN_NDN_ECRITICAL;
        }
    }
    if (r < 0)
        return r;
    return fragment->data ? LN_NDN_OK : LN_NDN_EUNSUPPORTED; /* none: an IDLE packet */
}

int ln_ndn_i_decode_reply(const uint8_t* buf, size_t size, ln_ndn_i_reply* out)
{
    ln_ndn_bytes rest, v;
    uint32_t type;
    found x;
    int r, lp = 0, nack = 0, data;
    ln_ndn_i_zero(out, sizeof *out);
    ln_ndn_i_zero(&x, sizeof x);
    rest.data = buf; /* NULL only with size 0 (pull_internal.h): tlv() reads nothing then */
    rest.size = size;
    /* LpPacket levels: ln_ndn_decode nests 2 deep per level, so the packet of a fourth is too
     * deep, and a Data's MetaInfo and SignatureInfo in a third */
    for (;;) {
        if ((r = tlv(&rest, &type, &v)) <= 0)
            return r < 0 ? r : LN_NDN_ETRUNCATED;
        if (rest.size)
            return LN_NDN_EMALFORMED;
        if (type != LN_NDN_T_LP_PACKET)
            break;
        if ((r = lp_headers(&v, &rest, &nack)) < 0)
            return r;
        if (++lp == 4)
            return LN_NDN_EDEPTH;
    }
    x.reply = out;
    x.deep = lp == 3;
    if (type != LN_NDN_T_INTEREST && type != LN_NDN_T_DATA)
        return LN_NDN_EUNSUPPORTED;
    out->type = (uint8_t)type;
    data = type == LN_NDN_T_DATA;
    if ((r = walk(&v, data ? G_DATA : G_INTEREST, data ? G_META : G_DATA, &x)) < 0)
        return r;
    if (!data) {
        out->lp_nack = (uint8_t)nack;
        return out->name.data ? LN_NDN_OK : LN_NDN_EMALFORMED;
    }
    if (!x.name_start || !x.has_sig_info || !x.has_sig_value)
        return LN_NDN_EMALFORMED;
    return nack ? LN_NDN_EMALFORMED : LN_NDN_OK; /* an LP Nack carries an Interest */
}

int ln_ndn_i_decode_content(const ln_ndn_bytes* content, ln_ndn_pull_content* out)
{
    found x;
    ln_ndn_i_zero(&x, sizeof x);
    ln_ndn_i_zero(out, sizeof *out);
    x.content = out;
    return walk(content, G_CONTENT, G_END, &x); /* on an error *out is not to be read */
}
#endif
