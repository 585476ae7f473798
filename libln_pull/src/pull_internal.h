/* pull_internal.h — what the consumer (pull_dit.c) needs from a received packet, and the
 * reply decoder that yields it (pull_decode.c): ln_ndn_decode's fields in a small view, from
 * the generic codec or, in a device's build (-DLN_NDN_CONSUMER), from a compact decoder with
 * the same acceptance rules and error codes.  Hidden (not installed, not exported). */
#ifndef LN_PULL_INTERNAL_H
#define LN_PULL_INTERNAL_H

#include <stddef.h>
#include <stdint.h>

#include "ln/ndn.h"

/* One received packet, views into it: a Data or an Interest (the one an NDNLPv2 Nack
 * carries). */
typedef struct ln_ndn_i_reply {
    ln_ndn_bytes name;           /* the Name TLV's value */
    ln_ndn_bytes content;        /* Data: Content's value */
    ln_ndn_bytes signed_portion; /* Data: Name through SignatureInfo */
    ln_ndn_bytes signature;      /* Data: SignatureValue's value */
    uint32_t content_type;       /* Data: LN_NDN_CONTENT_BLOB when absent */
    uint32_t signature_type;     /* Data */
    uint32_t nonce;              /* Interest, if has_nonce */
    uint8_t type;                /* LN_NDN_T_DATA or LN_NDN_T_INTEREST */
    uint8_t lp_nack;             /* an Interest in an LpPacket with a Nack header */
    uint8_t has_nonce;
} ln_ndn_i_reply;

/* Decodes one packet of exactly `size` bytes as ln_ndn_decode does (the same packets accepted,
 * the same error codes); `out` is zeroed first.  buf may be NULL only when size is 0.  A
 * device build without -DLN_PULL_HMAC (nothing verifies) leaves signed_portion, signature and
 * signature_type empty. */
int ln_ndn_i_decode_reply(const uint8_t* buf, size_t size, ln_ndn_i_reply* out);
/* ln_ndn_decode_pull_content (after an error, *out is not to be read). */
int ln_ndn_i_decode_content(const ln_ndn_bytes* content, ln_ndn_pull_content* out);
/* ln_ndn_name_next: a name component (type 1..65535) off the front of *rest; 1, 0 at the end
 * or an error. */
int ln_ndn_i_component(ln_ndn_bytes* rest, ln_ndn_component* out);
/* ln_ndn_read_nonneg. */
int ln_ndn_i_nonneg(const ln_ndn_bytes* value, uint64_t* out);

/* memset 0 / memcpy / "memcmp != 0" (in constant time).  A device's build has its own byte
 * loops: the C library's versions are several times larger and the consumer's copies are
 * short (a name, a struct). */
#ifdef LN_NDN_CONSUMER
void ln_ndn_i_zero(void* p, size_t n);
void ln_ndn_i_copy(void* to, const void* from, size_t n);
int ln_ndn_i_differ(const void* a, const void* b, size_t n);
#else
#include <string.h>
#define ln_ndn_i_zero(p, n) memset((p), 0, (n))
#define ln_ndn_i_copy memcpy
#define ln_ndn_i_differ memcmp
#endif

#endif
