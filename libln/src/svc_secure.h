/* svc_secure.h — the protected caller <-> provider channel of services between hosts
 * (docs/security.md, "Remote service calls"): the instance's service key from the manager,
 * the keys of one connection, and AEAD-sealed frames.  Only TCP connections use it; the Unix
 * socket stays plain.  Internal.
 *
 * On TCP the caller's first frame is SECURE (svc_wire.h) with a fresh nonce, the provider
 * answers SECURED with its own; both derive one key per direction from the service key, both
 * nonces, the level, the AEAD and the service name.  From then on every frame, both ways, is
 * one SEALED frame whose nonce is a per-direction counter (never sent, never reused): a
 * forged, replayed, reordered or cut frame fails to open. */
#ifndef LN_SVC_SECURE_H
#define LN_SVC_SECURE_H

#include <stddef.h>
#include <stdint.h>

#include "svc_wire.h"

#define LN_SVC_KEY_BYTES 32
#define LN_SVC_NONCE_BYTES 32 /* each side's handshake nonce */
#define LN_SVC_TAG_BYTES 16
/* Bytes a sealed frame has beyond the frame inside: its own header and the tag. */
#define LN_SVC_SEAL_OVERHEAD (LN_SVC_HEADER_SIZE + LN_SVC_TAG_BYTES)

/* The instance's `security` (client.schema SECURITY_*). */
enum ln_svc_level { LN_SVC_SEC_NONE = 0, LN_SVC_SEC_AUTHENTICATE = 1, LN_SVC_SEC_ENCRYPT = 2 };
/* AEADs, as bits of a SECURE offer. */
enum ln_svc_aead { LN_SVC_AEAD_CHACHA20 = 1, LN_SVC_AEAD_AES256GCM = 2 };

typedef struct ln_svc_key {
    int level; /* enum ln_svc_level */
    uint8_t key[LN_SVC_KEY_BYTES];
} ln_svc_key;

/* One direction's state is its key and its counter; a channel with level NONE is plain. */
typedef struct ln_svc_channel {
    int level;
    int aead;
    uint8_t tx_key[LN_SVC_KEY_BYTES], rx_key[LN_SVC_KEY_BYTES];
    uint64_t tx_seq, rx_seq;
} ln_svc_channel;

/* svc_key.c: the level and key the manager gives this client (SERVICE_KEY), asked for at
 * each new TCP connection, so a restarted manager's new key is used at once; if the manager
 * cannot be asked, the last key it gave.  LN_OK, or an error (recorded). */
int ln_svc_key_get(ln_client* clnt, ln_svc_key* out);
/* Opens a key the manager sealed under a session key (sealed = 1 of SERVICE_KEY_INFO):
 * `sealed` is nonce (16) || key xor pad (32) || tag (32), the tag also over `level`, the
 * level code that came with it.  LN_OK or LN_EPERM. */
int ln_svc_key_unseal(const uint8_t session_key[32], uint8_t level, const uint8_t* sealed,
                      size_t len, uint8_t key[LN_SVC_KEY_BYTES]);

/* The level's name ("none", "authenticate", "encrypt"), for texts. */
const char* ln_svc_level_name(int level);
/* The AEADs this host can use (AES-256-GCM only with the CPU's AES instructions). */
unsigned ln_svc_aead_offer(void);
/* The AEAD for two offers: AES-256-GCM if both have it, else ChaCha20-Poly1305; 0: none. */
int ln_svc_aead_pick(unsigned a, unsigned b);
/* A fresh handshake nonce. */
void ln_svc_nonce(uint8_t nonce[LN_SVC_NONCE_BYTES]);
/* Reads a handshake nonce (raw bytes); sets r->failed if fewer are left. */
void ln_svc_read_nonce(ln_rbuf* r, uint8_t nonce[LN_SVC_NONCE_BYTES]);
/* Derives the channel's keys (the caller's tx key is the provider's rx key).  LN_OK, or
 * LN_EINVAL for a level or AEAD it does not know. */
int ln_svc_channel_init(ln_svc_channel* ch, const ln_svc_key* key, int aead,
                        const uint8_t caller_nonce[LN_SVC_NONCE_BYTES],
                        const uint8_t provider_nonce[LN_SVC_NONCE_BYTES], const char* service,
                        int is_caller);
/* Forgets the keys: the channel is plain again. */
void ln_svc_channel_wipe(ln_svc_channel* ch);
/* Turns the one frame at b->data[start..len) into a SEALED frame in place.  LN_OK, the
 * wbuf's failure, or LN_ELIMIT once the counter is used up (the connection must end). */
int ln_svc_seal(ln_svc_channel* ch, ln_wbuf* b, size_t start);
/* Opens a whole SEALED frame in place (`frame` from its header, `len` bytes): LN_OK with the
 * frame inside, whose type, body and body size are returned; LN_EPERM if it fails
 * authentication (nothing of it may be used); LN_EPROTOCOL if what is inside is not one
 * whole frame of a type that may travel sealed. */
int ln_svc_open(ln_svc_channel* ch, uint8_t* frame, size_t len, uint16_t* type, uint8_t** body,
                size_t* body_len);

#endif /* LN_SVC_SECURE_H */
