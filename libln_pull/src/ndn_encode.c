/* ndn_encode.c — encoders into the caller's buffer: single TLVs, the Interest and the
 * NDNLPv2 LpPacket around a reply.  Data (which needs SHA-256) is in ndn_sign.c. */
#include <string.h>

#include "ndn_internal.h"

LN_NDN_EXPORT int ln_ndn_write_tlv(uint8_t* out, size_t cap, uint32_t type, const uint8_t* value,
                                   size_t size)
{
    size_t head;
    if ((!out && cap) || (!value && size))
        return LN_NDN_EINVAL;
    cap = LN_NDN_I_CLAMP(cap);
    if (size > cap)
        return LN_NDN_ESPACE;
    head = ln_ndn_i_varnum_size(type) + ln_ndn_i_varnum_size((uint32_t)size);
    if (head > cap - size)
        return LN_NDN_ESPACE;
    if (size)
        memmove(out + head, value, size);
    ln_ndn_i_put_header(out, type, size);
    return (int)(head + size);
}

LN_NDN_EXPORT int ln_ndn_write_nonneg_tlv(uint8_t* out, size_t cap, uint32_t type, uint64_t v)
{
    uint8_t b[8];
    return ln_ndn_write_tlv(out, cap, type, b, ln_ndn_i_put_nonneg(b, v));
}

/* One TLV at p (no bounds check: measured before); the position after it. */
static uint8_t* put_tlv(uint8_t* p, uint32_t type, const uint8_t* value, size_t size)
{
    p += ln_ndn_i_put_header(p, type, size);
    if (size)
        memmove(p, value, size);
    return p + size;
}

LN_NDN_EXPORT int ln_ndn_encode_interest(uint8_t* out, size_t cap, const ln_ndn_interest* in)
{
    uint8_t nonce[4], lifetime[8], *p;
    size_t life = 0, value, total;
    if (!in || (!out && cap) || !in->name.data || in->name.size == 0)
        return LN_NDN_EINVAL;
    if (in->app_parameters.size)
        return LN_NDN_EINVAL;
    cap = LN_NDN_I_CLAMP(cap);
    if (in->name.size > cap)
        return LN_NDN_ESPACE;
    nonce[0] = (uint8_t)(in->nonce >> 24); /* big-endian, like every number on the wire */
    nonce[1] = (uint8_t)(in->nonce >> 16);
    nonce[2] = (uint8_t)(in->nonce >> 8);
    nonce[3] = (uint8_t)in->nonce;
    if (in->lifetime_ms != LN_NDN_DEFAULT_LIFETIME_MS)
        life = ln_ndn_i_put_nonneg(lifetime, in->lifetime_ms);
    value = ln_ndn_i_tlv_size(LN_NDN_T_NAME, in->name.size) + (in->can_be_prefix ? 2 : 0) +
            (in->must_be_fresh ? 2 : 0) + 6 + (life ? 2 + life : 0) + (in->has_hop_limit ? 3 : 0);
    total = ln_ndn_i_tlv_size(LN_NDN_T_INTEREST, value);
    if (total > cap)
        return LN_NDN_ESPACE;
    p = out + ln_ndn_i_put_header(out, LN_NDN_T_INTEREST, value);
    p = put_tlv(p, LN_NDN_T_NAME, in->name.data, in->name.size);
    if (in->can_be_prefix)
        p = put_tlv(p, LN_NDN_T_CAN_BE_PREFIX, NULL, 0);
    if (in->must_be_fresh)
        p = put_tlv(p, LN_NDN_T_MUST_BE_FRESH, NULL, 0);
    p = put_tlv(p, LN_NDN_T_NONCE, nonce, 4);
    if (life)
        p = put_tlv(p, LN_NDN_T_INTEREST_LIFETIME, lifetime, life);
    if (in->has_hop_limit)
        p = put_tlv(p, LN_NDN_T_HOP_LIMIT, &in->hop_limit, 1);
    return (int)(p - out);
}

LN_NDN_EXPORT int ln_ndn_encode_lp(uint8_t* out, size_t cap, ln_ndn_bytes pit_token,
                                   const uint8_t* packet, size_t size)
{
    size_t token, value, total, p;
    if ((!out && cap) || !packet || size == 0 || (!pit_token.data && pit_token.size) ||
        pit_token.size > 32)
        return LN_NDN_EINVAL;
    cap = LN_NDN_I_CLAMP(cap);
    token = pit_token.size ? ln_ndn_i_tlv_size(LN_NDN_T_LP_PIT_TOKEN, pit_token.size) : 0;
    if (size > cap)
        return LN_NDN_ESPACE;
    value = token + ln_ndn_i_tlv_size(LN_NDN_T_LP_FRAGMENT, size);
    total = ln_ndn_i_tlv_size(LN_NDN_T_LP_PACKET, value);
    if (total > cap)
        return LN_NDN_ESPACE;
    memmove(out + total - size, packet, size); /* first: the packet may be inside out */
    p = ln_ndn_i_put_header(out, LN_NDN_T_LP_PACKET, value);
    if (token) {
        p += ln_ndn_i_put_header(out + p, LN_NDN_T_LP_PIT_TOKEN, pit_token.size);
        memmove(out + p, pit_token.data, pit_token.size);
        p += pit_token.size;
    }
    ln_ndn_i_put_header(out + p, LN_NDN_T_LP_FRAGMENT, size);
    return (int)total;
}
