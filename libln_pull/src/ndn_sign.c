/* ndn_sign.c — encoding of Data packets with their DigestSha256 or HMAC-SHA256 signature, and
 * verification of a decoded Data's signature (uses sha256.c). */
#include <string.h>

#include "ndn_internal.h"

static int check_signer(const ln_ndn_signer* signer)
{
    if (!signer)
        return LN_NDN_EINVAL;
    if (signer->type == LN_NDN_SIG_DIGEST_SHA256)
        return LN_NDN_OK;
    if (signer->type == LN_NDN_SIG_HMAC_SHA256 && (signer->key || !signer->key_size) &&
        (signer->key_name.data || !signer->key_name.size))
        return LN_NDN_OK;
    return LN_NDN_EINVAL;
}

static void sign(const ln_ndn_signer* signer, const uint8_t* p, size_t size, uint8_t out[32])
{
    ln_ndn_sha256 s;
    if (signer->type == LN_NDN_SIG_HMAC_SHA256) {
        ln_ndn_hmac_sha256(signer->key, signer->key_size, p, size, out);
        return;
    }
    ln_ndn_sha256_init(&s);
    ln_ndn_sha256_update(&s, p, size);
    ln_ndn_sha256_final(&s, out);
}

LN_NDN_EXPORT int ln_ndn_encode_data(uint8_t* out, size_t cap, const ln_ndn_data* d,
                                     const ln_ndn_signer* signer)
{
    size_t meta = 0, locator = 0, siginfo, value, total, p, signed_start;
    int r;
    if (!d || (!out && cap) || (!d->name.data && d->name.size) ||
        (!d->content.data && d->content.size))
        return LN_NDN_EINVAL;
    if ((r = check_signer(signer)) < 0)
        return r;
    cap = LN_NDN_I_CLAMP(cap);
    if (d->content_type != LN_NDN_CONTENT_BLOB)
        meta += 2 + ln_ndn_i_nonneg_size(d->content_type);
    if (d->freshness_ms)
        meta += 2 + ln_ndn_i_nonneg_size(d->freshness_ms);
    if (signer->type == LN_NDN_SIG_HMAC_SHA256 && signer->key_name.size)
        locator = ln_ndn_i_tlv_size(LN_NDN_T_KEY_LOCATOR,
                                    ln_ndn_i_tlv_size(LN_NDN_T_NAME, signer->key_name.size));
    siginfo = 3 + locator;
    if (d->name.size > cap || d->content.size > cap || signer->key_name.size > cap)
        return LN_NDN_ESPACE;
    value = ln_ndn_i_tlv_size(LN_NDN_T_NAME, d->name.size) +
            (meta ? ln_ndn_i_tlv_size(LN_NDN_T_META_INFO, meta) : 0) +
            ln_ndn_i_tlv_size(LN_NDN_T_CONTENT, d->content.size) +
            ln_ndn_i_tlv_size(LN_NDN_T_SIGNATURE_INFO, siginfo) + 2 + 32;
    total = ln_ndn_i_tlv_size(LN_NDN_T_DATA, value);
    if (value > cap || total > cap)
        return LN_NDN_ESPACE;
    p = ln_ndn_i_put_header(out, LN_NDN_T_DATA, value);
    signed_start = p;
    p += ln_ndn_i_put_header(out + p, LN_NDN_T_NAME, d->name.size);
    if (d->name.size)
        memmove(out + p, d->name.data, d->name.size);
    p += d->name.size;
    if (meta) {
        p += ln_ndn_i_put_header(out + p, LN_NDN_T_META_INFO, meta);
        if (d->content_type != LN_NDN_CONTENT_BLOB) {
            p += ln_ndn_i_put_header(out + p, LN_NDN_T_CONTENT_TYPE,
                                     ln_ndn_i_nonneg_size(d->content_type));
            p += ln_ndn_i_put_nonneg(out + p, d->content_type);
        }
        if (d->freshness_ms) {
            p += ln_ndn_i_put_header(out + p, LN_NDN_T_FRESHNESS_PERIOD,
                                     ln_ndn_i_nonneg_size(d->freshness_ms));
            p += ln_ndn_i_put_nonneg(out + p, d->freshness_ms);
        }
    }
    p += ln_ndn_i_put_header(out + p, LN_NDN_T_CONTENT, d->content.size);
    if (d->content.size)
        memmove(out + p, d->content.data, d->content.size);
    p += d->content.size;
    p += ln_ndn_i_put_header(out + p, LN_NDN_T_SIGNATURE_INFO, siginfo);
    p += ln_ndn_i_put_header(out + p, LN_NDN_T_SIGNATURE_TYPE, 1);
    out[p++] = (uint8_t)signer->type;
    if (locator) {
        p += ln_ndn_i_put_header(out + p, LN_NDN_T_KEY_LOCATOR,
                                 ln_ndn_i_tlv_size(LN_NDN_T_NAME, signer->key_name.size));
        p += ln_ndn_i_put_header(out + p, LN_NDN_T_NAME, signer->key_name.size);
        memmove(out + p, signer->key_name.data, signer->key_name.size);
        p += signer->key_name.size;
    }
    p += ln_ndn_i_put_header(out + p, LN_NDN_T_SIGNATURE_VALUE, 32);
    sign(signer, out + signed_start, p - 2 - signed_start, out + p);
    return (int)(p + 32);
}

LN_NDN_EXPORT int ln_ndn_verify(const ln_ndn_data* d, const ln_ndn_signer* signer)
{
    uint8_t expect[32], diff = 0;
    size_t i;
    if (!d || check_signer(signer) < 0 || d->signature_type != signer->type ||
        d->signature_value.size != 32 || !d->signed_portion.data)
        return LN_NDN_ESIGNATURE;
    sign(signer, d->signed_portion.data, d->signed_portion.size, expect);
    for (i = 0; i < 32; i++) /* in constant time */
        diff |= (uint8_t)(expect[i] ^ d->signature_value.data[i]);
    return diff ? LN_NDN_ESIGNATURE : LN_NDN_OK;
}
