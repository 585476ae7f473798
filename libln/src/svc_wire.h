/* svc_wire.h — the caller <-> provider protocol of services (docs/services.md, "Wire") and
 * the socket plumbing both sides share: frames, Unix/TCP listeners and connects and where a
 * provider's Unix socket lives (the host identity is ln_admin.h's ln_host_id()).  Internal. */
#ifndef LN_SVC_WIRE_H
#define LN_SVC_WIRE_H

#include <stddef.h>
#include <stdint.h>
#include <time.h>

#include "client_internal.h"
#include "proto.h"

#define LN_SVC_MAGIC 0x56534E4Cu /* "LNSV" */
#define LN_SVC_VERSION 1
#define LN_SVC_HEADER_SIZE 6 /* u32 length (type + body) + u16 type, as in the manager protocol */
/* Frame bytes besides the payload: the header, the type and the call id, with room to spare.
 * The maximum message size is about the payload; the frame may be this much bigger. */
#define LN_SVC_OVERHEAD 64
/* An ERROR frame's text, at most. */
#define LN_SVC_MAX_ERROR_TEXT 1024
/* A provider drops a caller that does not take its response within this time. */
#define LN_SVC_SEND_TIMEOUT 5.0

enum ln_svc_msg {
    LN_SVC_HELLO = 1,    /* c -> p: u32 magic, u16 version, str service, u64 layout_hash,
                            [str caller]: a provider takes HELLO with or without it */
    LN_SVC_WELCOME = 2,  /* p -> c: (empty) */
    LN_SVC_REQUEST = 3,  /* c -> p: u32 call_id, request payload (the rest of the frame) */
    LN_SVC_RESPONSE = 4, /* p -> c: u32 call_id, response payload (the rest of the frame) */
    LN_SVC_ERROR = 5,    /* p -> c: u32 call_id (0: about the connection), i32 code, str text */
    /* Recording calls (svc_tap.c): a recorder's first frame instead of HELLO, the provider's
     * answer, then one CALL per completed call, provider -> recorder only. */
    LN_SVC_TAP = 6,    /* r -> p: u32 magic, u16 version, str service, str recorder */
    LN_SVC_TAPPED = 7, /* p -> r: str md_name, u64 layout_hash, str provider, str signature */
    LN_SVC_CALL = 8,   /* p -> r: see svc_tap.h */
    /* Protected connections (TCP, security authenticate or encrypt; svc_secure.h): the
     * caller's first frame instead of HELLO, the provider's answer, then only SEALED frames,
     * each holding one of the frames above. */
    LN_SVC_SECURE = 9,   /* c -> p: u32 magic, u16 version, u16 level, u16 aead offer (bits),
                            str service, 32 bytes caller nonce */
    LN_SVC_SECURED = 10, /* p -> c: u16 level, u16 aead, 32 bytes provider nonce */
    LN_SVC_SEALED = 11,  /* both: a whole frame (encrypt: enciphered), then a 16-byte tag */
};

/* Checks a frame header: LN_OK with the body size and type; LN_EPROTOCOL for a length < 2 or
 * an unknown type; LN_ETOOBIG (body size and type still set) if the body would exceed
 * max_payload + LN_SVC_OVERHEAD. */
int ln_svc_parse_header(const uint8_t header[LN_SVC_HEADER_SIZE], size_t max_payload,
                        uint32_t* body_len, uint16_t* type);
/* Fills in the length of the frame started at `start` (ln_proto_frame_begin); LN_OK or the
 * wbuf's failure.  No size limit: the payload was limited when it was encoded. */
int ln_svc_frame_end(ln_wbuf* b, size_t start);
/* Appends a whole ERROR frame.  The text is cut to LN_SVC_MAX_ERROR_TEXT bytes at a UTF-8
 * boundary (and replaced if it is not UTF-8). */
void ln_svc_put_error(ln_wbuf* b, uint32_t call_id, int code, const char* text);

/* The directory for this client's service sockets: $LN_RUNTIME_DIR, else
 * $XDG_RUNTIME_DIR/ln/<instance>, else /tmp/ln-<uid>/<instance> (the manager's rule), created
 * with mode 0700 where missing.  LN_OK, or an error (recorded) when it cannot be used. */
int ln_svc_socket_dir(const char* instance, char* out, size_t size);

/* Listening sockets, non-blocking and close-on-exec.  Unix: at `path` (an existing file there
 * is an error); TCP: on every IPv4 address ($LN_SERVICE_BIND overrides), port chosen by the
 * kernel, returned in *port.  0 or an errno value. */
int ln_svc_listen_unix(const char* path, int* fd);
int ln_svc_listen_tcp(int* fd, uint16_t* port);
/* Non-blocking, close-on-exec connection to a Unix socket path, waiting until the deadline.
 * 0 or an errno value. */
int ln_svc_connect_unix(const char* path, const struct timespec* deadline, int* fd);

#endif /* LN_SVC_WIRE_H */
