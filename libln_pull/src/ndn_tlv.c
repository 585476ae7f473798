/* ndn_tlv.c — TLV primitives (VAR-NUMBER, NonNegativeInteger) and the decoder of bare and
 * NDNLPv2-wrapped Interest and Data packets into views of the caller's buffer.  Unknown
 * elements follow the evolvability rule (critical: type < 32 or odd); LP headers follow
 * NDNLPv2's rule (ignorable: 800..959 with the two low bits 00); nesting is bounded by
 * LN_NDN_MAX_DEPTH.  Compiled with -DLN_NDN_CONSUMER (a device's consumer-only build), an
 * Interest yields only its Name and Nonce (what an NDNLPv2 Nack needs). */
#include <string.h>

#include "ndn_internal.h"

LN_NDN_EXPORT int ln_ndn_read_varnum(const uint8_t* buf, size_t size, size_t* pos, uint64_t* out)
{
    size_t p = *pos, n, i;
    uint64_t v;
    if (p >= size)
        return LN_NDN_ETRUNCATED;
    v = buf[p++];
    n = v < 253 ? 0 : v == 253 ? 2 : v == 254 ? 4 : 8;
    if (n > size - p)
        return LN_NDN_ETRUNCATED;
    if (n) {
        v = 0;
        for (i = 0; i < n; i++)
            v = (v << 8) | buf[p++];
    }
    *pos = p;
    *out = v;
    return LN_NDN_OK;
}

LN_NDN_EXPORT int ln_ndn_read_nonneg(ln_ndn_bytes value, uint64_t* out)
{
    uint64_t v = 0;
    size_t i;
    if (value.size != 1 && value.size != 2 && value.size != 4 && value.size != 8)
        return LN_NDN_EMALFORMED;
    for (i = 0; i < value.size; i++)
        v = (v << 8) | value.data[i];
    *out = v;
    return LN_NDN_OK;
}

size_t ln_ndn_i_put_varnum(uint8_t* p, uint32_t v)
{
    size_t n, i;
    if (v < 253) {
        p[0] = (uint8_t)v;
        return 1;
    }
    n = v <= 0xffffu ? 2 : 4;
    p[0] = n == 2 ? 253 : 254;
    for (i = 0; i < n; i++)
        p[n - i] = (uint8_t)(v >> (8 * i));
    return n + 1;
}

size_t ln_ndn_i_put_nonneg(uint8_t* p, uint64_t v)
{
    size_t n = ln_ndn_i_nonneg_size(v), i;
    for (i = 0; i < n; i++)
        p[n - 1 - i] = (uint8_t)(v >> (8 * i));
    return n;
}

size_t ln_ndn_i_put_header(uint8_t* p, uint32_t type, size_t size)
{
    size_t n = ln_ndn_i_put_varnum(p, type);
    return n + ln_ndn_i_put_varnum(p + n, (uint32_t)size);
}

int ln_ndn_i_next(ln_ndn_bytes* rest, ln_ndn_i_tlv* out)
{
    size_t pos = 0;
    uint64_t length;
    int err;
    if (rest->size == 0)
        return 0;
    if ((err = ln_ndn_read_varnum(rest->data, rest->size, &pos, &out->type)) < 0 ||
        (err = ln_ndn_read_varnum(rest->data, rest->size, &pos, &length)) < 0)
        return err;
    if (length > rest->size - pos)
        return LN_NDN_ETRUNCATED;
    out->start = rest->data;
    out->value.data = rest->data + pos;
    out->value.size = (size_t)length;
    out->size = pos + (size_t)length;
    rest->data += out->size;
    rest->size -= out->size;
    return 1;
}

/* Walks the elements of `value`: each known one (in `order`, the grammar's sequence) must come
 * after the previous known one, else it counts as unknown; unknown ones follow the rule.
 * `field` gets each accepted element with its index in `order`. */
typedef int (*field_fn)(void* ctx, size_t index, const ln_ndn_i_tlv* t, int depth);

static int walk(ln_ndn_bytes value, const uint16_t* order, size_t n, field_fn field, void* ctx,
                int depth)
{
    ln_ndn_i_tlv t;
    size_t next = 0, i;
    int r;
    if (depth > LN_NDN_MAX_DEPTH)
        return LN_NDN_EDEPTH;
    while ((r = ln_ndn_i_next(&value, &t)) > 0) {
        for (i = next; i < n && order[i] != t.type; i++) {
        }
        if (i == n) {
            if (ln_ndn_i_critical(t.type))
                return LN_NDN_ECRITICAL;
            continue;
        }
        next = i + 1;
        if ((r = field(ctx, i, &t, depth)) < 0)
            return r;
    }
    return r;
}

/* A name value: every component a TLV with a type in 1..65535; at least `min` of them. */
static int check_name(ln_ndn_bytes name, size_t min)
{
    ln_ndn_component c;
    size_t n = 0;
    int r;
    while ((r = ln_ndn_name_next(&name, &c)) > 0)
        n++;
    if (r < 0)
        return r;
    return n < min ? LN_NDN_EMALFORMED : LN_NDN_OK;
}

#ifndef LN_NDN_CONSUMER
static int flag(const ln_ndn_i_tlv* t, uint8_t* out)
{
    if (t->value.size != 0)
        return LN_NDN_EMALFORMED;
    *out = 1;
    return LN_NDN_OK;
}
#endif

static uint32_t clamp32(uint64_t v) { return v > 0xffffffffu ? 0xffffffffu : (uint32_t)v; }

/* ---- Interest ---------------------------------------------------------------------------- */
static const uint16_t interest_order[] = {LN_NDN_T_NAME,
                                          LN_NDN_T_CAN_BE_PREFIX,
                                          LN_NDN_T_MUST_BE_FRESH,
                                          LN_NDN_T_FORWARDING_HINT,
                                          LN_NDN_T_NONCE,
                                          LN_NDN_T_INTEREST_LIFETIME,
                                          LN_NDN_T_HOP_LIMIT,
                                          LN_NDN_T_APP_PARAMETERS,
                                          0x2c /* InterestSignatureInfo */,
                                          0x2e /* InterestSignatureValue */};

static int interest_field(void* ctx, size_t index, const ln_ndn_i_tlv* t, int depth)
{
    ln_ndn_interest* in = ctx;
#ifndef LN_NDN_CONSUMER
    uint64_t v;
#endif
    int r;
    (void)depth;
    switch (t->type) {
    case LN_NDN_T_NAME:
        if ((r = check_name(t->value, 1)) < 0)
            return r;
        in->name = t->value;
        return LN_NDN_OK;
    case LN_NDN_T_NONCE:
        if (t->value.size != 4)
            return LN_NDN_EMALFORMED;
        in->nonce = (uint32_t)t->value.data[0] << 24 | (uint32_t)t->value.data[1] << 16 |
                    (uint32_t)t->value.data[2] << 8 | t->value.data[3];
        in->has_nonce = 1;
        return LN_NDN_OK;
#ifndef LN_NDN_CONSUMER /* a consumer-only build reads an Interest (an LP Nack) for these two */
    case LN_NDN_T_CAN_BE_PREFIX:
        return flag(t, &in->can_be_prefix);
    case LN_NDN_T_MUST_BE_FRESH:
        return flag(t, &in->must_be_fresh);
    case LN_NDN_T_INTEREST_LIFETIME:
        if ((r = ln_ndn_read_nonneg(t->value, &v)) < 0)
            return r;
        in->lifetime_ms = clamp32(v);
        return LN_NDN_OK;
    case LN_NDN_T_HOP_LIMIT:
        if (t->value.size != 1)
            return LN_NDN_EMALFORMED;
        in->hop_limit = t->value.data[0];
        in->has_hop_limit = 1;
        return LN_NDN_OK;
    case LN_NDN_T_APP_PARAMETERS:
        in->app_parameters = t->value;
        return LN_NDN_OK;
#endif
    default: /* ForwardingHint and the Interest signature: accepted, not used */
        (void)index;
        return LN_NDN_OK;
    }
}

static int decode_interest(ln_ndn_bytes value, ln_ndn_interest* in, int depth)
{
    int r;
    in->lifetime_ms = LN_NDN_DEFAULT_LIFETIME_MS;
    r = walk(value, interest_order, sizeof interest_order / sizeof interest_order[0],
             interest_field, in, depth);
    if (r < 0)
        return r;
    return in->name.data ? LN_NDN_OK : LN_NDN_EMALFORMED;
}

/* ---- Data -------------------------------------------------------------------------------- */
static const uint16_t data_order[] = {LN_NDN_T_NAME, LN_NDN_T_META_INFO, LN_NDN_T_CONTENT,
                                      LN_NDN_T_SIGNATURE_INFO, LN_NDN_T_SIGNATURE_VALUE};
static const uint16_t meta_order[] = {LN_NDN_T_CONTENT_TYPE, LN_NDN_T_FRESHNESS_PERIOD,
                                      LN_NDN_T_FINAL_BLOCK_ID};
static const uint16_t siginfo_order[] = {LN_NDN_T_SIGNATURE_TYPE, LN_NDN_T_KEY_LOCATOR};

typedef struct data_ctx {
    ln_ndn_data* d;
    const uint8_t* name_start;
    uint8_t has_sig_type, has_sig_info, has_sig_value;
} data_ctx;

static int meta_field(void* ctx, size_t index, const ln_ndn_i_tlv* t, int depth)
{
    ln_ndn_data* d = ((data_ctx*)ctx)->d;
    ln_ndn_bytes rest = t->value;
    ln_ndn_component c;
    uint64_t v;
    int r;
    (void)index;
    (void)depth;
    switch (t->type) {
    case LN_NDN_T_CONTENT_TYPE:
        if ((r = ln_ndn_read_nonneg(t->value, &v)) < 0)
            return r;
        d->content_type = clamp32(v);
        return LN_NDN_OK;
    case LN_NDN_T_FRESHNESS_PERIOD:
        if ((r = ln_ndn_read_nonneg(t->value, &v)) < 0)
            return r;
        d->freshness_ms = clamp32(v);
        return LN_NDN_OK;
    default: /* FinalBlockId: exactly one name component */
        if ((r = ln_ndn_name_next(&rest, &c)) < 0)
            return r;
        return r == 1 && rest.size == 0 ? LN_NDN_OK : LN_NDN_EMALFORMED;
    }
}

static int siginfo_field(void* ctx, size_t index, const ln_ndn_i_tlv* t, int depth)
{
    data_ctx* c = ctx;
    uint64_t v;
    int r;
    (void)index;
    (void)depth;
    if (t->type == LN_NDN_T_SIGNATURE_TYPE) {
        if ((r = ln_ndn_read_nonneg(t->value, &v)) < 0)
            return r;
        c->d->signature_type = clamp32(v);
        c->has_sig_type = 1;
    } else {
        c->d->key_locator = t->value;
    }
    return LN_NDN_OK;
}

static int data_field(void* ctx, size_t index, const ln_ndn_i_tlv* t, int depth)
{
    data_ctx* c = ctx;
    int r;
    (void)index;
    switch (t->type) {
    case LN_NDN_T_NAME:
        if ((r = check_name(t->value, 0)) < 0)
            return r;
        c->d->name = t->value;
        c->name_start = t->start;
        return LN_NDN_OK;
    case LN_NDN_T_META_INFO:
        return walk(t->value, meta_order, 3, meta_field, c, depth + 1);
    case LN_NDN_T_CONTENT:
        c->d->content = t->value;
        return LN_NDN_OK;
    case LN_NDN_T_SIGNATURE_INFO:
        if ((r = walk(t->value, siginfo_order, 2, siginfo_field, c, depth + 1)) < 0)
            return r;
        if (!c->has_sig_type || !c->name_start)
            return LN_NDN_EMALFORMED;
        c->has_sig_info = 1;
        c->d->signed_portion.data = c->name_start;
        c->d->signed_portion.size = (size_t)(t->start + t->size - c->name_start);
        return LN_NDN_OK;
    default:
        c->d->signature_value = t->value;
        c->has_sig_value = 1;
        return LN_NDN_OK;
    }
}

static int decode_data(ln_ndn_bytes value, ln_ndn_data* d, int depth)
{
    data_ctx c;
    int r;
    memset(&c, 0, sizeof c);
    c.d = d;
    r = walk(value, data_order, 5, data_field, &c, depth);
    if (r < 0)
        return r;
    if (!c.name_start || !c.has_sig_info || !c.has_sig_value)
        return LN_NDN_EMALFORMED;
    return LN_NDN_OK;
}

/* ---- packets and NDNLPv2 ------------------------------------------------------------------ */
static int decode_packet(const uint8_t* buf, size_t size, ln_ndn_packet* out, int depth);

static int decode_lp(ln_ndn_bytes value, ln_ndn_packet* out, int depth)
{
    ln_ndn_i_tlv t, n;
    ln_ndn_bytes fragment = {NULL, 0}, rest;
    uint64_t v;
    int r, nack = 0;
    if (depth > LN_NDN_MAX_DEPTH)
        return LN_NDN_EDEPTH;
    while ((r = ln_ndn_i_next(&value, &t)) > 0) {
        if (fragment.data) /* nothing may follow the fragment (no trailer fields are known) */
            return LN_NDN_EMALFORMED;
        switch (t.type) {
        case LN_NDN_T_LP_FRAGMENT:
            fragment = t.value;
            if (!fragment.data || !fragment.size)
                return LN_NDN_EMALFORMED;
            break;
        case LN_NDN_T_LP_PIT_TOKEN:
            if (t.value.size < 1 || t.value.size > 32)
                return LN_NDN_EMALFORMED;
            out->pit_token = t.value;
            break;
        case LN_NDN_T_LP_NACK:
            nack = 1;
            rest = t.value;
            while ((r = ln_ndn_i_next(&rest, &n)) > 0) {
                if (n.type == LN_NDN_T_LP_NACK_REASON) {
                    if ((r = ln_ndn_read_nonneg(n.value, &v)) < 0)
                        return r;
                    out->nack_reason = clamp32(v);
                } else if (ln_ndn_i_critical(n.type)) {
                    return LN_NDN_ECRITICAL;
                }
            }
            if (r < 0)
                return r;
            break;
        case 0x52: /* FragIndex */
        case 0x53: /* FragCount: more than one fragment is reassembly, which is unsupported */
            if ((r = ln_ndn_read_nonneg(t.value, &v)) < 0)
                return r;
            if ((t.type == 0x53 && v != 1) || (t.type == 0x52 && v != 0))
                return LN_NDN_EUNSUPPORTED;
            break;
        case 0x51: /* Sequence: only used with fragmentation or reliability */
            break;
        default:
            if (!(t.type >= 800 && t.type <= 959 && (t.type & 3u) == 0))
                return LN_NDN_ECRITICAL;
        }
    }
    if (r < 0)
        return r;
    if (!fragment.data) /* an IDLE packet (acks only): nothing for us */
        return LN_NDN_EUNSUPPORTED;
    out->lp = 1;
    r = decode_packet(fragment.data, fragment.size, out, depth + 1);
    if (r < 0)
        return r;
    if (nack) {
        if (out->type != LN_NDN_T_INTEREST)
            return LN_NDN_EMALFORMED;
        out->lp_nack = 1;
    }
    return LN_NDN_OK;
}

static int decode_packet(const uint8_t* buf, size_t size, ln_ndn_packet* out, int depth)
{
    ln_ndn_bytes rest;
    ln_ndn_i_tlv t;
    int r;
    if (depth > LN_NDN_MAX_DEPTH)
        return LN_NDN_EDEPTH;
    rest.data = buf;
    rest.size = size;
    if ((r = ln_ndn_i_next(&rest, &t)) < 0)
        return r;
    if (r == 0)
        return LN_NDN_ETRUNCATED;
    if (rest.size != 0)
        return LN_NDN_EMALFORMED;
    switch (t.type) {
    case LN_NDN_T_INTEREST:
        memset(&out->interest, 0, sizeof out->interest);
        out->type = LN_NDN_T_INTEREST;
        return decode_interest(t.value, &out->interest, depth + 1);
    case LN_NDN_T_DATA:
        memset(&out->data, 0, sizeof out->data);
        out->type = LN_NDN_T_DATA;
        return decode_data(t.value, &out->data, depth + 1);
    case LN_NDN_T_LP_PACKET:
        return decode_lp(t.value, out, depth + 1);
    default:
        return LN_NDN_EUNSUPPORTED;
    }
}

LN_NDN_EXPORT int ln_ndn_decode(const uint8_t* buf, size_t size, ln_ndn_packet* out)
{
    int r;
    if (!out || (!buf && size))
        return LN_NDN_EINVAL;
    memset(out, 0, sizeof *out);
    r = decode_packet(buf, size, out, 1);
    if (r < 0)
        memset(out, 0, sizeof *out);
    return r;
}
