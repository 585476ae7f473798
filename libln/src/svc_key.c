/* svc_key.c — the instance's service key and level as the manager gives them (SERVICE_KEY,
 * docs/security.md "Remote service calls"): asked for at each new TCP connection of a caller
 * or a provider, opened if the manager sealed it under the connection's session key, and
 * remembered for when the manager cannot be asked. */
#include <string.h>

#include <sodium.h>

#include "client_conn.h"
#include "svc_secure.h"

#define SEAL_NONCE 16
#define SEAL_TAG 32
#define SEALED_BYTES (SEAL_NONCE + LN_SVC_KEY_BYTES + SEAL_TAG)
static const char pad_label[] = "ln service key pad v1";
static const char tag_label[] = "ln service key tag v2";

/* The key is kept in the client under its state lock (a leaf lock: nothing is called while
 * it is held). */
static void remember(ln_client* clnt, const ln_svc_key* key)
{
    pthread_mutex_lock(&clnt->state_lock);
    clnt->svc_key_known = 1;
    clnt->svc_key_level = key->level;
    memcpy(clnt->svc_key, key->key, sizeof clnt->svc_key);
    pthread_mutex_unlock(&clnt->state_lock);
}

static int recall(ln_client* clnt, ln_svc_key* key)
{
    pthread_mutex_lock(&clnt->state_lock);
    int known = clnt->svc_key_known;
    key->level = clnt->svc_key_level;
    memcpy(key->key, clnt->svc_key, sizeof key->key);
    pthread_mutex_unlock(&clnt->state_lock);
    return known;
}

int ln_svc_key_unseal(const uint8_t session_key[32], uint8_t level, const uint8_t* sealed,
                      size_t len, uint8_t key[LN_SVC_KEY_BYTES])
{
    if (len != SEALED_BYTES || sodium_init() < 0)
        return LN_EPERM;
    const uint8_t* nonce = sealed;
    const uint8_t* box = sealed + SEAL_NONCE;
    uint8_t mac[SEAL_TAG], pad[crypto_auth_hmacsha256_BYTES];
    crypto_auth_hmacsha256_state st;
    crypto_auth_hmacsha256_init(&st, session_key, 32);
    crypto_auth_hmacsha256_update(&st, (const uint8_t*)tag_label, sizeof tag_label - 1);
    crypto_auth_hmacsha256_update(&st, &level, 1);
    crypto_auth_hmacsha256_update(&st, nonce, SEAL_NONCE);
    crypto_auth_hmacsha256_update(&st, box, LN_SVC_KEY_BYTES);
    crypto_auth_hmacsha256_final(&st, mac);
    if (sodium_memcmp(mac, box + LN_SVC_KEY_BYTES, SEAL_TAG) != 0) {
        sodium_memzero(&st, sizeof st);
        return LN_EPERM;
    }
    crypto_auth_hmacsha256_init(&st, session_key, 32);
    crypto_auth_hmacsha256_update(&st, (const uint8_t*)pad_label, sizeof pad_label - 1);
    crypto_auth_hmacsha256_update(&st, nonce, SEAL_NONCE);
    crypto_auth_hmacsha256_final(&st, pad);
    for (size_t i = 0; i < LN_SVC_KEY_BYTES; i++)
        key[i] = box[i] ^ pad[i];
    sodium_memzero(pad, sizeof pad);
    sodium_memzero(&st, sizeof st);
    return LN_OK;
}

/* The SERVICE_KEY_INFO body into *out (recorded errors). */
static int take_info(ln_client* clnt, ln_rbuf* reply, ln_svc_key* out)
{
    ln_msg_service_key_info info;
    uint8_t raw[SEALED_BYTES];
    size_t len = 0;
    if (ln_msg_service_key_info_read_after_id(reply, &info) != LN_OK ||
        info.security > LN_SVC_SEC_ENCRYPT || info.key.len % 2 != 0 ||
        info.key.len / 2 > sizeof raw ||
        sodium_hex2bin(raw, sizeof raw, info.key.s, info.key.len, NULL, &len, NULL) != 0)
        return ln_set_error(clnt, LN_EPROTOCOL, "malformed SERVICE_KEY_INFO from manager %s",
                            clnt->address);
    out->level = info.security;
    uint8_t session[32];
    const int has_session = ln_client_session_key(clnt, session) == LN_OK;
    if (has_session && !info.sealed) { /* the manager seals for key-admitted clients, always */
        sodium_memzero(session, sizeof session);
        sodium_memzero(raw, sizeof raw);
        return ln_set_error(clnt, LN_EPERM,
                            "the service key from manager %s is not sealed although this "
                            "connection has a session key (altered on the way?)",
                            clnt->address);
    }
    if (!info.sealed && out->level == LN_SVC_SEC_NONE)
        return LN_OK;
    if (info.sealed) {
        int rc = has_session ? LN_OK : LN_ENOTFOUND;
        if (rc == LN_OK)
            rc = ln_svc_key_unseal(session, info.security, raw, len, out->key);
        sodium_memzero(session, sizeof session);
        sodium_memzero(raw, sizeof raw);
        if (rc != LN_OK)
            return ln_set_error(clnt, LN_EPERM,
                                "the service key from manager %s does not open with this "
                                "connection's session key",
                                clnt->address);
        return LN_OK;
    }
    if (len != LN_SVC_KEY_BYTES)
        return ln_set_error(clnt, LN_EPROTOCOL, "manager %s sent a service key of %zu bytes",
                            clnt->address, len);
    memcpy(out->key, raw, LN_SVC_KEY_BYTES);
    sodium_memzero(raw, sizeof raw);
    return LN_OK;
}

int ln_svc_key_get(ln_client* clnt, ln_svc_key* out)
{
    uint16_t reply_type;
    ln_rbuf reply;
    int rc = ln_client_request(clnt, LN_MSG_SERVICE_KEY, NULL, &reply_type, &reply);
    if (rc == LN_OK) {
        rc = take_info(clnt, &reply, out);
        if (rc == LN_OK)
            remember(clnt, out);
        return rc;
    }
    if (rc == LN_ECONNECTION && recall(clnt, out))
        return LN_OK; /* the manager is away: the key it gave last still holds */
    return ln_set_error(clnt, rc, "cannot get the service key from manager %s: %s", clnt->address,
                        ln_last_error());
}
