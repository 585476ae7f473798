/* test_svc_secure.c — sealed frames of services between hosts (libln/src/svc_secure.c): both
 * sides derive matching keys, each level round-trips, encrypt hides the frame and authenticate
 * does not, and a flipped byte, a replayed, reordered or cut frame, a wrong key, another
 * service name or nonce all fail to open; the sealed service key (svc_key.c) opens only with
 * its session key. */
#define _GNU_SOURCE 1
#include <stdlib.h>
#include <string.h>

#include <sodium.h>

#include "ln_test.h"
#include "svc_secure.h"

static const uint8_t nc[LN_SVC_NONCE_BYTES] = {1, 2, 3};
static const uint8_t np[LN_SVC_NONCE_BYTES] = {4, 5, 6};

static ln_svc_key key_of(int level, uint8_t fill)
{
    ln_svc_key k = {.level = level};
    memset(k.key, fill, sizeof k.key);
    return k;
}

/* A caller and a provider channel for `level` with the service key filled with `fill`. */
static void pair(int level, int aead, ln_svc_channel* caller, ln_svc_channel* provider)
{
    ln_svc_key k = key_of(level, 0x42);
    LN_CHECK_EQ(ln_svc_channel_init(caller, &k, aead, nc, np, "arm.echo", 1), LN_OK);
    LN_CHECK_EQ(ln_svc_channel_init(provider, &k, aead, nc, np, "arm.echo", 0), LN_OK);
}

/* One REQUEST frame with `text` as its payload, sealed by ch into b. */
static void sealed_request(ln_svc_channel* ch, ln_wbuf* b, uint32_t call_id, const char* text)
{
    ln_wbuf_reset(b);
    size_t start = ln_proto_frame_begin(b, LN_SVC_REQUEST);
    ln_wbuf_u32(b, call_id);
    ln_wbuf_bytes(b, text, strlen(text));
    LN_CHECK_EQ(ln_svc_frame_end(b, start), LN_OK);
    LN_CHECK_EQ(ln_svc_seal(ch, b, start), LN_OK);
}

/* Opens a copy of `frame` (opening works in place). */
static int open_copy(ln_svc_channel* ch, const uint8_t* frame, size_t len, uint16_t* type,
                     uint8_t* copy, uint8_t** body, size_t* body_len)
{
    memcpy(copy, frame, len);
    return ln_svc_open(ch, copy, len, type, body, body_len);
}

static void test_round_trip(int level, int aead)
{
    ln_svc_channel c, p;
    pair(level, aead, &c, &p);
    ln_wbuf b;
    ln_wbuf_init(&b);
    uint8_t copy[256];
    for (uint32_t i = 1; i <= 3; i++) {
        sealed_request(&c, &b, i, "move the arm");
        LN_CHECK_EQ(b.data[4], LN_SVC_SEALED);
        LN_CHECK_EQ(b.len, LN_SVC_SEAL_OVERHEAD + LN_SVC_HEADER_SIZE + 4 + 12);
        int visible = memmem(b.data, b.len, "move the arm", 12) != NULL;
        LN_CHECK_EQ(visible, level == LN_SVC_SEC_AUTHENTICATE);
        uint16_t type;
        uint8_t* body;
        size_t len;
        LN_CHECK_EQ(open_copy(&p, b.data, b.len, &type, copy, &body, &len), LN_OK);
        LN_CHECK_EQ(type, LN_SVC_REQUEST);
        LN_CHECK_EQ(len, 4 + 12);
        LN_CHECK(memcmp(body + 4, "move the arm", 12) == 0);
        LN_CHECK_EQ(body[0], i);
    }
    /* The other direction has its own key: the caller cannot open its own frame. */
    sealed_request(&c, &b, 9, "x");
    uint16_t type;
    uint8_t* body;
    size_t len;
    LN_CHECK_EQ(open_copy(&c, b.data, b.len, &type, copy, &body, &len), LN_EPERM);
    ln_wbuf_free(&b);
}

static void test_levels_and_aeads(void)
{
    test_round_trip(LN_SVC_SEC_AUTHENTICATE, LN_SVC_AEAD_CHACHA20);
    test_round_trip(LN_SVC_SEC_ENCRYPT, LN_SVC_AEAD_CHACHA20);
    if (ln_svc_aead_offer() & LN_SVC_AEAD_AES256GCM) {
        test_round_trip(LN_SVC_SEC_AUTHENTICATE, LN_SVC_AEAD_AES256GCM);
        test_round_trip(LN_SVC_SEC_ENCRYPT, LN_SVC_AEAD_AES256GCM);
    }
    LN_CHECK_EQ(ln_svc_aead_pick(3, 3), LN_SVC_AEAD_AES256GCM);
    LN_CHECK_EQ(ln_svc_aead_pick(1, 3), LN_SVC_AEAD_CHACHA20);
    LN_CHECK_EQ(ln_svc_aead_pick(2, 1), 0);
    ln_svc_channel ch;
    ln_svc_key none = key_of(LN_SVC_SEC_NONE, 0);
    LN_CHECK_EQ(ln_svc_channel_init(&ch, &none, LN_SVC_AEAD_CHACHA20, nc, np, "a", 1), LN_EINVAL);
}

/* Every way a frame can be altered on the way fails to open, at both levels. */
static void test_tampering(int level)
{
    ln_svc_channel c, p;
    pair(level, LN_SVC_AEAD_CHACHA20, &c, &p);
    ln_wbuf first, second;
    ln_wbuf_init(&first);
    ln_wbuf_init(&second);
    sealed_request(&c, &first, 1, "first request");
    sealed_request(&c, &second, 2, "second request");
    uint8_t copy[256];
    uint16_t type;
    uint8_t* body;
    size_t len;
    for (size_t at = 0; at < second.len; at++) { /* each byte flipped, header included */
        ln_svc_channel q = p;
        LN_CHECK_EQ(open_copy(&q, first.data, first.len, &type, copy, &body, &len), LN_OK);
        memcpy(copy, second.data, second.len);
        copy[at] ^= 0x80;
        LN_CHECK_EQ(ln_svc_open(&q, copy, second.len, &type, &body, &len), LN_EPERM);
    }
    ln_svc_channel q = p;
    /* reordered: the second first */
    LN_CHECK_EQ(open_copy(&q, second.data, second.len, &type, copy, &body, &len), LN_EPERM);
    q = p;
    LN_CHECK_EQ(open_copy(&q, first.data, first.len, &type, copy, &body, &len), LN_OK);
    /* replayed */
    LN_CHECK_EQ(open_copy(&q, first.data, first.len, &type, copy, &body, &len), LN_EPERM);
    /* cut, with and without a length that matches */
    q = p;
    LN_CHECK_EQ(open_copy(&q, first.data, first.len - 1, &type, copy, &body, &len), LN_EPERM);
    memcpy(copy, first.data, first.len);
    copy[0] = (uint8_t)(copy[0] - 4);
    LN_CHECK_EQ(ln_svc_open(&q, copy, first.len - 4, &type, &body, &len), LN_EPERM);
    LN_CHECK_EQ(open_copy(&q, first.data, 10, &type, copy, &body, &len), LN_EPERM);
    /* another key, another service, another nonce */
    ln_svc_key other = key_of(level, 0x43), same = key_of(level, 0x42);
    LN_CHECK_EQ(ln_svc_channel_init(&q, &other, LN_SVC_AEAD_CHACHA20, nc, np, "arm.echo", 0),
                LN_OK);
    LN_CHECK_EQ(open_copy(&q, first.data, first.len, &type, copy, &body, &len), LN_EPERM);
    LN_CHECK_EQ(ln_svc_channel_init(&q, &same, LN_SVC_AEAD_CHACHA20, nc, np, "arm.other", 0),
                LN_OK);
    LN_CHECK_EQ(open_copy(&q, first.data, first.len, &type, copy, &body, &len), LN_EPERM);
    LN_CHECK_EQ(ln_svc_channel_init(&q, &same, LN_SVC_AEAD_CHACHA20, np, np, "arm.echo", 0), LN_OK);
    LN_CHECK_EQ(open_copy(&q, first.data, first.len, &type, copy, &body, &len), LN_EPERM);
    ln_wbuf_free(&first);
    ln_wbuf_free(&second);
}

static void test_tampering_both_levels(void)
{
    test_tampering(LN_SVC_SEC_AUTHENTICATE);
    test_tampering(LN_SVC_SEC_ENCRYPT);
}

/* An authentic frame whose inside is not one frame: a protocol error, not an attack. */
static void test_bad_inner_frame(void)
{
    ln_svc_channel c, p;
    pair(LN_SVC_SEC_ENCRYPT, LN_SVC_AEAD_CHACHA20, &c, &p);
    ln_wbuf b;
    ln_wbuf_init(&b);
    ln_wbuf_bytes(&b, "\x09\0\0\0\x03\0abc", 9); /* length says 9, 5 follow */
    LN_CHECK_EQ(ln_svc_seal(&c, &b, 0), LN_OK);
    uint16_t type;
    uint8_t* body;
    size_t len;
    LN_CHECK_EQ(ln_svc_open(&p, b.data, b.len, &type, &body, &len), LN_EPROTOCOL);
    ln_wbuf_free(&b);
}

/* The key sealed as the manager's service_security.py seal() does it. */
static void test_unseal(void)
{
    uint8_t session[32], key[32], sealed[80], out[32];
    memset(session, 7, sizeof session);
    memset(key, 0xab, sizeof key);
    randombytes_buf(sealed, 16);
    uint8_t pad[32], tag[32];
    crypto_auth_hmacsha256_state st;
    crypto_auth_hmacsha256_init(&st, session, 32);
    crypto_auth_hmacsha256_update(&st, (const uint8_t*)"ln service key pad v1", 21);
    crypto_auth_hmacsha256_update(&st, sealed, 16);
    crypto_auth_hmacsha256_final(&st, pad);
    for (int i = 0; i < 32; i++)
        sealed[16 + i] = key[i] ^ pad[i];
    crypto_auth_hmacsha256_init(&st, session, 32);
    const uint8_t level = LN_SVC_SEC_ENCRYPT;
    crypto_auth_hmacsha256_update(&st, (const uint8_t*)"ln service key tag v2", 21);
    crypto_auth_hmacsha256_update(&st, &level, 1);
    crypto_auth_hmacsha256_update(&st, sealed, 48);
    crypto_auth_hmacsha256_final(&st, tag);
    memcpy(sealed + 48, tag, 32);
    LN_CHECK_EQ(ln_svc_key_unseal(session, level, sealed, sizeof sealed, out), LN_OK);
    LN_CHECK(memcmp(out, key, 32) == 0);
    /* a level lowered on the way does not open */
    LN_CHECK_EQ(ln_svc_key_unseal(session, LN_SVC_SEC_NONE, sealed, sizeof sealed, out), LN_EPERM);
    sealed[20] ^= 1;
    LN_CHECK_EQ(ln_svc_key_unseal(session, level, sealed, sizeof sealed, out), LN_EPERM);
    sealed[20] ^= 1;
    session[0] ^= 1;
    LN_CHECK_EQ(ln_svc_key_unseal(session, level, sealed, sizeof sealed, out), LN_EPERM);
    LN_CHECK_EQ(ln_svc_key_unseal(session, level, sealed, 79, out), LN_EPERM);
}

int main(void)
{
    LN_CHECK(sodium_init() >= 0);
    LN_TEST_RUN(test_levels_and_aeads);
    LN_TEST_RUN(test_tampering_both_levels);
    LN_TEST_RUN(test_bad_inner_frame);
    LN_TEST_RUN(test_unseal);
    LN_TEST_EXIT();
}
