/* svc_secure.c — keys and sealed frames of services between hosts (svc_secure.h): the key
 * derivation of one connection and the AEAD (AES-256-GCM or ChaCha20-Poly1305-IETF, libsodium)
 * that seals and opens its frames with counter nonces. */
#include <string.h>

#include <sodium.h>

#include "svc_secure.h"

#define KDF_LABEL "ln service channel v1"
#define KDF_CONTEXT "lnsvcdir" /* crypto_kdf contexts are 8 bytes */
#define SUBKEY_TO_PROVIDER 1
#define SUBKEY_TO_CALLER 2

const char* ln_svc_level_name(int level)
{
    switch (level) {
    case LN_SVC_SEC_NONE:
        return "none";
    case LN_SVC_SEC_AUTHENTICATE:
        return "authenticate";
    case LN_SVC_SEC_ENCRYPT:
        return "encrypt";
    default:
        return "unknown";
    }
}

unsigned ln_svc_aead_offer(void)
{
    if (sodium_init() < 0)
        return 0;
    return LN_SVC_AEAD_CHACHA20 |
           (crypto_aead_aes256gcm_is_available() ? (unsigned)LN_SVC_AEAD_AES256GCM : 0u);
}

int ln_svc_aead_pick(unsigned a, unsigned b)
{
    unsigned both = a & b;
    if (both & LN_SVC_AEAD_AES256GCM)
        return LN_SVC_AEAD_AES256GCM;
    return both & LN_SVC_AEAD_CHACHA20 ? LN_SVC_AEAD_CHACHA20 : 0;
}

void ln_svc_nonce(uint8_t nonce[LN_SVC_NONCE_BYTES])
{
    if (sodium_init() < 0)
        memset(nonce, 0, LN_SVC_NONCE_BYTES); /* randombytes_buf still fills it */
    randombytes_buf(nonce, LN_SVC_NONCE_BYTES);
}

void ln_svc_read_nonce(ln_rbuf* r, uint8_t nonce[LN_SVC_NONCE_BYTES])
{
    if (r->failed || r->left < LN_SVC_NONCE_BYTES) {
        r->failed = LN_EPROTOCOL;
        memset(nonce, 0, LN_SVC_NONCE_BYTES);
        return;
    }
    memcpy(nonce, r->p, LN_SVC_NONCE_BYTES);
    r->p += LN_SVC_NONCE_BYTES;
    r->left -= LN_SVC_NONCE_BYTES;
}

int ln_svc_channel_init(ln_svc_channel* ch, const ln_svc_key* key, int aead,
                        const uint8_t caller_nonce[LN_SVC_NONCE_BYTES],
                        const uint8_t provider_nonce[LN_SVC_NONCE_BYTES], const char* service,
                        int is_caller)
{
    memset(ch, 0, sizeof *ch);
    if ((key->level != LN_SVC_SEC_AUTHENTICATE && key->level != LN_SVC_SEC_ENCRYPT) ||
        (aead != LN_SVC_AEAD_CHACHA20 && aead != LN_SVC_AEAD_AES256GCM) || sodium_init() < 0)
        return LN_EINVAL;
    /* The connection's master key binds everything both sides agreed on, so a SECURED
     * answer altered on the way gives both sides different keys and the first frame fails. */
    uint8_t master[crypto_kdf_KEYBYTES];
    uint8_t params[2] = {(uint8_t)key->level, (uint8_t)aead};
    crypto_generichash_state st;
    crypto_generichash_init(&st, key->key, LN_SVC_KEY_BYTES, sizeof master);
    crypto_generichash_update(&st, (const uint8_t*)KDF_LABEL, sizeof KDF_LABEL);
    crypto_generichash_update(&st, params, sizeof params);
    crypto_generichash_update(&st, caller_nonce, LN_SVC_NONCE_BYTES);
    crypto_generichash_update(&st, provider_nonce, LN_SVC_NONCE_BYTES);
    crypto_generichash_update(&st, (const uint8_t*)service, strlen(service));
    crypto_generichash_final(&st, master, sizeof master);
    uint8_t to_provider[LN_SVC_KEY_BYTES], to_caller[LN_SVC_KEY_BYTES];
    crypto_kdf_derive_from_key(to_provider, sizeof to_provider, SUBKEY_TO_PROVIDER, KDF_CONTEXT,
                               master);
    crypto_kdf_derive_from_key(to_caller, sizeof to_caller, SUBKEY_TO_CALLER, KDF_CONTEXT, master);
    memcpy(ch->tx_key, is_caller ? to_provider : to_caller, LN_SVC_KEY_BYTES);
    memcpy(ch->rx_key, is_caller ? to_caller : to_provider, LN_SVC_KEY_BYTES);
    sodium_memzero(master, sizeof master);
    sodium_memzero(to_provider, sizeof to_provider);
    sodium_memzero(to_caller, sizeof to_caller);
    sodium_memzero(&st, sizeof st);
    ch->level = key->level;
    ch->aead = aead;
    return LN_OK;
}

void ln_svc_channel_wipe(ln_svc_channel* ch) { sodium_memzero(ch, sizeof *ch); }

/* The AEAD nonce of message `seq` of one direction: the counter, little-endian, then zeros.
 * Each direction has its own key, so the same counter in both directions is no reuse. */
static void counter_nonce(uint64_t seq, uint8_t npub[12])
{
    memset(npub, 0, 12);
    for (int i = 0; i < 8; i++)
        npub[i] = (uint8_t)(seq >> (8 * i));
}

/* Encrypts m[0..mlen) in place into c (m == c allowed) and writes the tag. */
static void aead_seal(int aead, const uint8_t key[32], uint64_t seq, uint8_t* c,
                      unsigned long long mlen, const uint8_t* ad, unsigned long long adlen,
                      uint8_t tag[LN_SVC_TAG_BYTES])
{
    uint8_t npub[12];
    counter_nonce(seq, npub);
    if (aead == LN_SVC_AEAD_AES256GCM)
        crypto_aead_aes256gcm_encrypt_detached(c, tag, NULL, c, mlen, ad, adlen, NULL, npub, key);
    else
        crypto_aead_chacha20poly1305_ietf_encrypt_detached(c, tag, NULL, c, mlen, ad, adlen, NULL,
                                                           npub, key);
}

/* Checks the tag and decrypts c[0..clen) in place: 0, or -1 if it does not authenticate. */
static int aead_open(int aead, const uint8_t key[32], uint64_t seq, uint8_t* c,
                     unsigned long long clen, const uint8_t* ad, unsigned long long adlen,
                     const uint8_t tag[LN_SVC_TAG_BYTES])
{
    uint8_t npub[12];
    counter_nonce(seq, npub);
    if (aead == LN_SVC_AEAD_AES256GCM)
        return crypto_aead_aes256gcm_decrypt_detached(c, NULL, c, clen, tag, ad, adlen, npub, key);
    return crypto_aead_chacha20poly1305_ietf_decrypt_detached(c, NULL, c, clen, tag, ad, adlen,
                                                              npub, key);
}

static void put_header(uint8_t* at, uint32_t length, uint16_t type)
{
    for (int i = 0; i < 4; i++)
        at[i] = (uint8_t)(length >> (8 * i));
    at[4] = (uint8_t)type;
    at[5] = (uint8_t)(type >> 8);
}

int ln_svc_seal(ln_svc_channel* ch, ln_wbuf* b, size_t start)
{
    static const uint8_t room[LN_SVC_SEAL_OVERHEAD];
    if (b->failed)
        return b->failed;
    if (ch->tx_seq == UINT64_MAX)
        return LN_ELIMIT;
    size_t n = b->len - start; /* the frame inside, header included */
    ln_wbuf_bytes(b, room, sizeof room);
    if (b->failed)
        return b->failed;
    if (n + 2 + LN_SVC_TAG_BYTES > UINT32_MAX)
        return LN_ETOOBIG;
    uint8_t* frame = b->data + start;
    memmove(frame + LN_SVC_HEADER_SIZE, frame, n);
    put_header(frame, (uint32_t)(2 + n + LN_SVC_TAG_BYTES), LN_SVC_SEALED);
    uint8_t* inner = frame + LN_SVC_HEADER_SIZE;
    uint8_t* tag = inner + n;
    if (ch->level == LN_SVC_SEC_ENCRYPT) /* the header in the clear, the frame inside hidden */
        aead_seal(ch->aead, ch->tx_key, ch->tx_seq, inner, n, frame, LN_SVC_HEADER_SIZE, tag);
    else /* authenticate: everything in the clear, covered by the tag */
        aead_seal(ch->aead, ch->tx_key, ch->tx_seq, tag, 0, frame, LN_SVC_HEADER_SIZE + n, tag);
    ch->tx_seq++;
    return LN_OK;
}

int ln_svc_open(ln_svc_channel* ch, uint8_t* frame, size_t len, uint16_t* type, uint8_t** body,
                size_t* body_len)
{
    if (len < LN_SVC_SEAL_OVERHEAD || ch->rx_seq == UINT64_MAX)
        return LN_EPERM;
    size_t n = len - LN_SVC_SEAL_OVERHEAD;
    uint8_t* inner = frame + LN_SVC_HEADER_SIZE;
    const uint8_t* tag = inner + n;
    uint8_t none[1];
    int bad = ch->level == LN_SVC_SEC_ENCRYPT ? aead_open(ch->aead, ch->rx_key, ch->rx_seq, inner,
                                                          n, frame, LN_SVC_HEADER_SIZE, tag)
                                              : aead_open(ch->aead, ch->rx_key, ch->rx_seq, none, 0,
                                                          frame, LN_SVC_HEADER_SIZE + n, tag);
    if (bad != 0)
        return LN_EPERM;
    ch->rx_seq++;
    /* Authentic, so a bad frame inside is the peer's mistake, not an attack. */
    ln_rbuf r;
    ln_rbuf_init(&r, inner, n);
    uint32_t length = ln_rbuf_u32(&r);
    uint16_t t = ln_rbuf_u16(&r);
    if (r.failed || (size_t)length + 4 != n || t < LN_SVC_HELLO || t > LN_SVC_CALL)
        return LN_EPROTOCOL;
    *type = t;
    *body = inner + LN_SVC_HEADER_SIZE;
    *body_len = n - LN_SVC_HEADER_SIZE;
    return LN_OK;
}
