/* sha256.c — SHA-256 as FIPS 180-4 defines it and HMAC-SHA256 as RFC 2104 defines it, for the
 * DigestSha256 and HMAC-SHA256 signatures of Data.  Needed by the producer and by a consumer
 * that verifies (ln_pull_set_verify_key; a device's "hmac" profile).  Sized for small cores:
 * a 16-word message schedule (64 bytes of stack, not 256), no 64-bit shifts, and in a
 * device's build (-DLN_NDN_CONSUMER) none of the C library's functions. */
#include "ln/ndn.h"
#include "pull_internal.h"

static const uint32_t K[64] = {
    0x428a2f98, 0x71374491, 0xb5c0fbcf, 0xe9b5dba5, 0x3956c25b, 0x59f111f1, 0x923f82a4, 0xab1c5ed5,
    0xd807aa98, 0x12835b01, 0x243185be, 0x550c7dc3, 0x72be5d74, 0x80deb1fe, 0x9bdc06a7, 0xc19bf174,
    0xe49b69c1, 0xefbe4786, 0x0fc19dc6, 0x240ca1cc, 0x2de92c6f, 0x4a7484aa, 0x5cb0a9dc, 0x76f988da,
    0x983e5152, 0xa831c66d, 0xb00327c8, 0xbf597fc7, 0xc6e00bf3, 0xd5a79147, 0x06ca6351, 0x14292967,
    0x27b70a85, 0x2e1b2138, 0x4d2c6dfc, 0x53380d13, 0x650a7354, 0x766a0abb, 0x81c2c92e, 0x92722c85,
    0xa2bfe8a1, 0xa81a664b, 0xc24b8b70, 0xc76c51a3, 0xd192e819, 0xd6990624, 0xf40e3585, 0x106aa070,
    0x19a4c116, 0x1e376c08, 0x2748774c, 0x34b0bcb5, 0x391c0cb3, 0x4ed8aa4a, 0x5b9cca4f, 0x682e6ff3,
    0x748f82ee, 0x78a5636f, 0x84c87814, 0x8cc70208, 0x90befffa, 0xa4506ceb, 0xbef9a3f7, 0xc67178f2};

#define ROTR(x, n) (((x) >> (n)) | ((x) << (32 - (n))))

static void compress(uint32_t h[8], const uint8_t block[64])
{
    uint32_t w[16], a, b, c, d, e, f, g, k, t1, t2;
    int i;
    for (i = 0; i < 16; i++)
        w[i] = (uint32_t)block[4 * i] << 24 | (uint32_t)block[4 * i + 1] << 16 |
               (uint32_t)block[4 * i + 2] << 8 | block[4 * i + 3];
    a = h[0], b = h[1], c = h[2], d = h[3], e = h[4], f = h[5], g = h[6], k = h[7];
    for (i = 0; i < 64; i++) {
        if (i >= 16) { /* W[i], in place of W[i - 16]: w holds the last 16 */
            uint32_t w15 = w[(i - 15) & 15], w2 = w[(i - 2) & 15];
            uint32_t s0 = ROTR(w15, 7) ^ ROTR(w15, 18) ^ (w15 >> 3);
            uint32_t s1 = ROTR(w2, 17) ^ ROTR(w2, 19) ^ (w2 >> 10);
            w[i & 15] += s0 + w[(i - 7) & 15] + s1;
        }
        t1 = k + (ROTR(e, 6) ^ ROTR(e, 11) ^ ROTR(e, 25)) + ((e & f) ^ (~e & g)) + K[i] + w[i & 15];
        t2 = (ROTR(a, 2) ^ ROTR(a, 13) ^ ROTR(a, 22)) + ((a & b) ^ (a & c) ^ (b & c));
        k = g, g = f, f = e, e = d + t1, d = c, c = b, b = a, a = t1 + t2;
    }
    h[0] += a, h[1] += b, h[2] += c, h[3] += d, h[4] += e, h[5] += f, h[6] += g, h[7] += k;
}

LN_NDN_EXPORT void ln_ndn_sha256_init(ln_ndn_sha256* s)
{
    static const uint32_t H0[8] = {0x6a09e667, 0xbb67ae85, 0x3c6ef372, 0xa54ff53a,
                                   0x510e527f, 0x9b05688c, 0x1f83d9ab, 0x5be0cd19};
    ln_ndn_i_copy(s->h, H0, sizeof H0);
    s->bytes = 0;
    s->fill = 0;
}

LN_NDN_EXPORT void ln_ndn_sha256_update(ln_ndn_sha256* s, const void* data, size_t size)
{
    const uint8_t* p = data;
    s->bytes += size;
    while (size) {
        size_t n = 64 - s->fill < size ? 64 - s->fill : size;
        ln_ndn_i_copy(s->block + s->fill, p, n);
        s->fill += n, p += n, size -= n;
        if (s->fill == 64) {
            compress(s->h, s->block);
            s->fill = 0;
        }
    }
}

LN_NDN_EXPORT void ln_ndn_sha256_final(ln_ndn_sha256* s, uint8_t out[32])
{
    /* the message's length in bits, big-endian: two 32-bit halves (no 64-bit shifts) */
    uint32_t hi = (uint32_t)(s->bytes >> 29), lo = (uint32_t)s->bytes << 3;
    int i;
    s->block[s->fill++] = 0x80;
    if (s->fill > 56) {
        ln_ndn_i_zero(s->block + s->fill, 64 - s->fill);
        compress(s->h, s->block);
        s->fill = 0;
    }
    ln_ndn_i_zero(s->block + s->fill, 56 - s->fill);
    for (i = 0; i < 4; i++) {
        s->block[56 + i] = (uint8_t)(hi >> (24 - 8 * i));
        s->block[60 + i] = (uint8_t)(lo >> (24 - 8 * i));
    }
    compress(s->h, s->block);
    for (i = 0; i < 32; i++)
        out[i] = (uint8_t)(s->h[i / 4] >> (24 - 8 * (i % 4)));
    ln_ndn_i_zero(s, sizeof *s);
}

LN_NDN_EXPORT void ln_ndn_hmac_sha256(const uint8_t* key, size_t key_size, const void* data,
                                      size_t size, uint8_t out[32])
{
    uint8_t k[64];
    ln_ndn_sha256 s;
    int i, outer;
    ln_ndn_i_zero(k, sizeof k);
    if (key_size > 64) {
        ln_ndn_sha256_init(&s);
        ln_ndn_sha256_update(&s, key, key_size);
        ln_ndn_sha256_final(&s, k);
    } else if (key_size) {
        ln_ndn_i_copy(k, key, key_size);
    }
    /* H(K ^ ipad || data) into out, then H(K ^ opad || out): the pads made in k itself */
    for (outer = 0; outer < 2; outer++) {
        for (i = 0; i < 64; i++)
            k[i] ^= outer ? 0x36 ^ 0x5c : 0x36;
        ln_ndn_sha256_init(&s);
        ln_ndn_sha256_update(&s, k, 64);
        ln_ndn_sha256_update(&s, outer ? out : data, outer ? 32 : size);
        ln_ndn_sha256_final(&s, out);
    }
}
