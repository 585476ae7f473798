/* client_auth.h — the client's side of admission by key (docs/security.md, "Client admission
 * to the manager"): finding and reading the client key file, the HMAC-SHA256 proofs of the
 * CHALLENGE/AUTH exchange and the session key both sides derive.  Used by client_conn.c. */
#ifndef LN_CLIENT_AUTH_H
#define LN_CLIENT_AUTH_H

#include <stddef.h>
#include <stdint.h>

#define LN_AUTH_BYTES 32                    /* keys, nonces and proofs */
#define LN_AUTH_HEX (2 * LN_AUTH_BYTES)     /* their hex form on the wire */
#define LN_AUTH_CLIENT "ln client proof v1" /* labels: one per use of the key */
#define LN_AUTH_MANAGER "ln manager proof v1"
#define LN_AUTH_SESSION "ln session key v1"

/* The client key: $LN_CLIENT_KEY_FILE, else ~/.config/links_and_nodes/client.key if that
 * exists.  LN_OK with the key and the file's path in `path`; LN_ENOTFOUND (text in `err`) if
 * there is no key file; LN_EPERM (text in `err`) if the file is unusable: not a regular file,
 * not ours, readable by group or others, or not 64 hex digits plus an optional newline. */
int ln_auth_load_key(uint8_t key[LN_AUTH_BYTES], char* path, size_t path_size, char* err,
                     size_t err_size);

/* HMAC-SHA256 under `key` of label, 0, instance, 0, client name, 0, the manager's nonce, the
 * client's nonce: a proof (label LN_AUTH_CLIENT / LN_AUTH_MANAGER) or the session key. */
void ln_auth_mac(const uint8_t key[LN_AUTH_BYTES], const char* label, const char* instance,
                 const char* name, const uint8_t manager_nonce[LN_AUTH_BYTES],
                 const uint8_t client_nonce[LN_AUTH_BYTES], uint8_t out[LN_AUTH_BYTES]);

/* Fresh random bytes (libsodium). */
void ln_auth_random(uint8_t* out, size_t n);
/* 0 if a and b are equal, in time independent of their contents. */
int ln_auth_differ(const uint8_t a[LN_AUTH_BYTES], const uint8_t b[LN_AUTH_BYTES]);
/* Wipes n bytes so the compiler cannot drop it. */
void ln_auth_wipe(void* p, size_t n);

/* Lowercase hex of 32 bytes into out[LN_AUTH_HEX + 1]. */
void ln_auth_to_hex(const uint8_t in[LN_AUTH_BYTES], char out[LN_AUTH_HEX + 1]);
/* Parses exactly LN_AUTH_HEX hex digits of `len` bytes at `s`; 0 or -1. */
int ln_auth_from_hex(const char* s, size_t len, uint8_t out[LN_AUTH_BYTES]);

#endif /* LN_CLIENT_AUTH_H */
