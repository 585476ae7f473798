/* ln/ndn.h — the subset of the NDN packet format 0.3 (TLV) that pull topics use: decoding
 * bare and NDNLPv2-wrapped Interest and Data packets into views of the caller's buffer,
 * encoding them into the caller's buffer, names from and to URIs, and the DigestSha256 and
 * HMAC-SHA256 signatures.  Portable C99: no malloc, no threads, no system calls.  Shared by
 * the tiny consumer (ln/pull.h) and the producer in ln_daemon; docs/pull.md explains it. */
#ifndef LN_NDN_H
#define LN_NDN_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#if defined(__GNUC__) || defined(__clang__)
#define LN_NDN_EXPORT __attribute__((visibility("default")))
#else
#define LN_NDN_EXPORT
#endif

/* ---- errors: every function that can fail returns >= 0 or one code of this table --------- */
#define LN_NDN_ERRNO_MAP(XX)                                                                       \
    XX(ETRUNCATED, -1, "truncated TLV")                                                            \
    XX(EMALFORMED, -2, "malformed TLV")                                                            \
    XX(ECRITICAL, -3, "unknown critical TLV element")                                              \
    XX(ESPACE, -4, "output buffer too small")                                                      \
    XX(EUNSUPPORTED, -5, "not an Interest or Data packet")                                         \
    XX(ENAME, -6, "bad name")                                                                      \
    XX(ESIGNATURE, -7, "signature does not verify")                                                \
    XX(EINVAL, -8, "invalid argument")                                                             \
    XX(EDEPTH, -9, "TLV nested too deep")

enum ln_ndn_error {
#define LN_NDN_ENUM_(name, code, text) LN_NDN_##name = (code),
    LN_NDN_OK = 0,
    LN_NDN_ERRNO_MAP(LN_NDN_ENUM_)
#undef LN_NDN_ENUM_
};
LN_NDN_EXPORT const char* ln_ndn_strerror(int code);

/* ---- TLV type numbers (NDN packet format 0.3, NDNLPv2) ------------------------------------ */
enum {
    LN_NDN_T_INTEREST = 0x05,
    LN_NDN_T_DATA = 0x06,
    LN_NDN_T_NAME = 0x07,
    LN_NDN_T_GENERIC = 0x08,
    LN_NDN_T_IMPLICIT_DIGEST = 0x01,
    LN_NDN_T_PARAMS_DIGEST = 0x02,
    LN_NDN_T_SEQUENCE_NUM = 0x3a,
    LN_NDN_T_CAN_BE_PREFIX = 0x21,
    LN_NDN_T_MUST_BE_FRESH = 0x12,
    LN_NDN_T_FORWARDING_HINT = 0x1e,
    LN_NDN_T_NONCE = 0x0a,
    LN_NDN_T_INTEREST_LIFETIME = 0x0c,
    LN_NDN_T_HOP_LIMIT = 0x22,
    LN_NDN_T_APP_PARAMETERS = 0x24,
    LN_NDN_T_META_INFO = 0x14,
    LN_NDN_T_CONTENT = 0x15,
    LN_NDN_T_SIGNATURE_INFO = 0x16,
    LN_NDN_T_SIGNATURE_VALUE = 0x17,
    LN_NDN_T_CONTENT_TYPE = 0x18,
    LN_NDN_T_FRESHNESS_PERIOD = 0x19,
    LN_NDN_T_FINAL_BLOCK_ID = 0x1a,
    LN_NDN_T_SIGNATURE_TYPE = 0x1b,
    LN_NDN_T_KEY_LOCATOR = 0x1c,
    LN_NDN_T_LP_PACKET = 0x64,
    LN_NDN_T_LP_FRAGMENT = 0x50,
    LN_NDN_T_LP_PIT_TOKEN = 0x62,
    LN_NDN_T_LP_NACK = 0x0320,
    LN_NDN_T_LP_NACK_REASON = 0x0321,
    /* Pull-topic content header (application types 128..252, even: non-critical) */
    LN_NDN_T_PULL_LATEST = 0x80,  /* NonNegativeInteger: the producer's newest seq */
    LN_NDN_T_PULL_TIME = 0x82,    /* NonNegativeInteger: publish time, µs (CLOCK_REALTIME) */
    LN_NDN_T_PULL_PERIOD = 0x84,  /* NonNegativeInteger: mean publish period, µs */
    LN_NDN_T_PULL_PAYLOAD = 0x86, /* the sample's bytes (the md layout) */
};
enum { LN_NDN_CONTENT_BLOB = 0, LN_NDN_CONTENT_NACK = 3 };
enum { LN_NDN_SIG_DIGEST_SHA256 = 0, LN_NDN_SIG_HMAC_SHA256 = 4 };
#define LN_NDN_DEFAULT_LIFETIME_MS 4000u
#define LN_NDN_MAX_DEPTH 8 /* nesting the decoder follows (LpPacket > Data > MetaInfo > ...) */

/* A view of bytes in a caller's buffer; size 0 (data may be NULL) when absent. */
typedef struct ln_ndn_bytes {
    const uint8_t* data;
    size_t size;
} ln_ndn_bytes;

/* A decoded Interest: views into the packet.  `name` is the Name TLV's value (its
 * components, each a TLV). */
typedef struct ln_ndn_interest {
    ln_ndn_bytes name;
    uint32_t nonce;
    uint32_t lifetime_ms; /* LN_NDN_DEFAULT_LIFETIME_MS when absent */
    uint8_t has_nonce;
    uint8_t can_be_prefix;
    uint8_t must_be_fresh;
    uint8_t has_hop_limit;
    uint8_t hop_limit;
    ln_ndn_bytes app_parameters;
} ln_ndn_interest;

/* A decoded Data packet (also what ln_ndn_encode_data takes: name, content_type,
 * freshness_ms and content are read, the signature fields are filled in by the signer). */
typedef struct ln_ndn_data {
    ln_ndn_bytes name;
    uint32_t content_type; /* LN_NDN_CONTENT_BLOB when absent */
    uint32_t freshness_ms; /* 0 when absent */
    ln_ndn_bytes content;
    uint32_t signature_type;
    ln_ndn_bytes key_locator; /* value of SignatureInfo's KeyLocator, if any */
    ln_ndn_bytes signature_value;
    ln_ndn_bytes signed_portion; /* Name through SignatureInfo: what the signature covers */
} ln_ndn_data;

/* A received packet: a bare Interest or Data, or one inside an NDNLPv2 LpPacket Fragment
 * (unknown LP headers are skipped by the evolvability rule).  An LpPacket with a Nack header
 * carries the Interest that was refused. */
typedef struct ln_ndn_packet {
    uint32_t type;   /* LN_NDN_T_INTEREST or LN_NDN_T_DATA */
    uint8_t lp;      /* it came in an LpPacket */
    uint8_t lp_nack; /* ... with a Nack header */
    uint32_t nack_reason;
    ln_ndn_bytes pit_token;   /* echo it in an LpPacket around the reply when size > 0 */
    ln_ndn_interest interest; /* when type is LN_NDN_T_INTEREST */
    ln_ndn_data data;         /* when type is LN_NDN_T_DATA */
} ln_ndn_packet;

/* Decodes one packet of exactly `size` bytes; LN_NDN_OK or an error (nothing is read beyond
 * `size`, TLVs nest at most LN_NDN_MAX_DEPTH deep, an unknown element with an odd type or a
 * type below 32 is LN_NDN_ECRITICAL, an even one is skipped). */
LN_NDN_EXPORT int ln_ndn_decode(const uint8_t* buf, size_t size, ln_ndn_packet* out);

/* ---- TLV primitives ------------------------------------------------------------------- */
/* Reads a VAR-NUMBER at *pos (< size): advances *pos; LN_NDN_ETRUNCATED if it is cut off. */
LN_NDN_EXPORT int ln_ndn_read_varnum(const uint8_t* buf, size_t size, size_t* pos, uint64_t* out);
/* A NonNegativeInteger value of 1, 2, 4 or 8 bytes; LN_NDN_EMALFORMED for other sizes. */
LN_NDN_EXPORT int ln_ndn_read_nonneg(ln_ndn_bytes value, uint64_t* out);

/* ---- names ---------------------------------------------------------------------------- */
typedef struct ln_ndn_component {
    uint32_t type; /* LN_NDN_T_GENERIC, LN_NDN_T_SEQUENCE_NUM, ... */
    ln_ndn_bytes value;
} ln_ndn_component;
/* The next component of a name value; 1 if one was taken off the front of *rest, 0 at the
 * end, or an error. */
LN_NDN_EXPORT int ln_ndn_name_next(ln_ndn_bytes* rest, ln_ndn_component* out);
/* A name value from a URI ("/robot/arm.state/seq=42", "%xx" escapes, "seq=N" typed
 * components); its size or an error (LN_NDN_ENAME for a bad URI, LN_NDN_ESPACE). */
LN_NDN_EXPORT int ln_ndn_name_from_uri(uint8_t* out, size_t cap, const char* uri);
/* The URI of a name value, NUL-terminated; its length or an error. */
LN_NDN_EXPORT int ln_ndn_name_to_uri(char* out, size_t cap, ln_ndn_bytes name);
/* Appends a component to a name value of *size bytes in out[cap]; the new size or error. */
LN_NDN_EXPORT int ln_ndn_name_append(uint8_t* out, size_t cap, size_t size, uint32_t type,
                                     const uint8_t* value, size_t value_size);
LN_NDN_EXPORT int ln_ndn_name_append_seq(uint8_t* out, size_t cap, size_t size, uint64_t seq);
/* 1 if `prefix` is a prefix of `name` (whole components), else 0. */
LN_NDN_EXPORT int ln_ndn_name_has_prefix(ln_ndn_bytes name, ln_ndn_bytes prefix);

/* ---- encoding (into the caller's buffer; the packet's size or an error) ----------------- */
/* Interest: name, nonce (always written), lifetime (written unless it is the default),
 * can_be_prefix, must_be_fresh, hop limit if has_hop_limit.  app_parameters unsupported. */
LN_NDN_EXPORT int ln_ndn_encode_interest(uint8_t* out, size_t cap, const ln_ndn_interest* in);

/* How Data is signed: DigestSha256 (key ignored), or HMAC-SHA256 with the key (the
 * KeyLocator then holds key_name, a name value, if its size > 0). */
typedef struct ln_ndn_signer {
    uint32_t type; /* LN_NDN_SIG_DIGEST_SHA256 or LN_NDN_SIG_HMAC_SHA256 */
    const uint8_t* key;
    size_t key_size;
    ln_ndn_bytes key_name;
} ln_ndn_signer;
/* Data: name, MetaInfo (ContentType unless BLOB, FreshnessPeriod unless 0), Content (always,
 * possibly empty), SignatureInfo and SignatureValue by the signer. */
LN_NDN_EXPORT int ln_ndn_encode_data(uint8_t* out, size_t cap, const ln_ndn_data* d,
                                     const ln_ndn_signer* signer);
/* LN_NDN_OK if the decoded Data's signature verifies with the signer's type and key,
 * LN_NDN_ESIGNATURE if not (or of another type). */
LN_NDN_EXPORT int ln_ndn_verify(const ln_ndn_data* d, const ln_ndn_signer* signer);

/* Wraps `packet` in an LpPacket with a PitToken (the reply to a packet that had one). */
LN_NDN_EXPORT int ln_ndn_encode_lp(uint8_t* out, size_t cap, ln_ndn_bytes pit_token,
                                   const uint8_t* packet, size_t size);

/* Writers of single TLVs, for content headers: the bytes written or an error. */
LN_NDN_EXPORT int ln_ndn_write_nonneg_tlv(uint8_t* out, size_t cap, uint32_t type, uint64_t v);
LN_NDN_EXPORT int ln_ndn_write_tlv(uint8_t* out, size_t cap, uint32_t type, const uint8_t* value,
                                   size_t size);

/* ---- pull-topic content: header TLVs then the payload ---------------------------------- */
typedef struct ln_ndn_pull_content {
    uint64_t latest_seq;  /* 0 when absent */
    uint64_t publish_us;  /* 0 when absent */
    uint64_t period_us;   /* 0 when absent */
    ln_ndn_bytes payload; /* absent in a NACK */
} ln_ndn_pull_content;
LN_NDN_EXPORT int ln_ndn_encode_pull_content(uint8_t* out, size_t cap,
                                             const ln_ndn_pull_content* c);
/* Unknown even types are skipped, unknown odd ones are LN_NDN_ECRITICAL. */
LN_NDN_EXPORT int ln_ndn_decode_pull_content(ln_ndn_bytes content, ln_ndn_pull_content* out);

/* ---- SHA-256 (FIPS 180-4) and HMAC-SHA256 (RFC 2104) ------------------------------------ */
typedef struct ln_ndn_sha256 {
    uint32_t h[8];
    uint64_t bytes;
    uint8_t block[64];
    size_t fill;
} ln_ndn_sha256;
LN_NDN_EXPORT void ln_ndn_sha256_init(ln_ndn_sha256* s);
LN_NDN_EXPORT void ln_ndn_sha256_update(ln_ndn_sha256* s, const void* data, size_t size);
LN_NDN_EXPORT void ln_ndn_sha256_final(ln_ndn_sha256* s, uint8_t out[32]);
LN_NDN_EXPORT void ln_ndn_hmac_sha256(const uint8_t* key, size_t key_size, const void* data,
                                      size_t size, uint8_t out[32]);

#ifdef __cplusplus
}
#endif
#endif
