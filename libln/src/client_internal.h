/* client_internal.h — what the rest of libln (ports, services) uses of a client: error
 * recording, handle checks, request/answer round trips with the manager, and the registry
 * of ports that ln_client_destroy closes.  Never installed. */
#ifndef LN_CLIENT_INTERNAL_H
#define LN_CLIENT_INTERNAL_H

#include <pthread.h>
#include <stdarg.h>
#include <sys/types.h>

#include "ln_internal.h"
#include "proto.h"

/* Handle tag: ln_client functions return LN_EBADHANDLE on mismatch. */
#define LN_CLIENT_MAGIC 0x4c4e434cu
/* Bytes of a last-error text, NUL included; longer texts are cut. */
#define LN_ERROR_TEXT_MAX 2048

/* Records `code` and a printf-style text as the calling thread's last error (ln_last_error())
 * and, if clnt != NULL, as the client's last error; returns code so callers can
 * `return ln_set_error(...)`.  The arguments may include ln_last_error() itself, to put
 * context in front of an earlier error.  errno is preserved. */
int ln_set_error(ln_client* clnt, int code, const char* fmt, ...)
    __attribute__((format(printf, 3, 4)));
/* Same, with the code mapped from errno value `err` (ENOMEM -> ENOMEM, EACCES/EPERM -> EPERM,
 * ETIMEDOUT -> ETIMEOUT, ECONNREFUSED/ECONNRESET/EPIPE/ENOTCONN and the other "network or
 * peer gone" errnos -> ECONNECTION, EINTR -> EINTR, else ESYS) and ": strerror(err)"
 * appended to the text. */
int ln_set_errno_error(ln_client* clnt, int err, const char* fmt, ...)
    __attribute__((format(printf, 3, 4)));
/* The mapping alone. */
int ln_errno_to_code(int err);

/* LN_OK, or LN_EBADHANDLE (NULL or bad magic; also recorded as the thread's last error). */
int ln_client_check(const ln_client* clnt);

/* Send request `type` with `body` (the fields AFTER the request id; the function prepends a
 * fresh non-zero request id; NULL means no further fields) and wait up to the client's timeout
 * for the answer with that id.  On an ERROR answer: records its text as is and returns its
 * code.  On success: *reply_type is the answer's type (always the one `type` succeeds with,
 * e.g. PORT_OK for PUBLISH) and *reply reads the answer's body after the request id (a copy
 * owned by the calling thread, valid until its next ln_client_request); its fields
 * were already checked against docs/protocol.md, so reading them cannot fail.  Serialized by
 * the client's mutex (thread-safe).
 * Connection loss -> LN_ECONNECTION (later calls fail fast with LN_ECONNECTION until the
 * reconnect monitor has a new connection, or for good without one); malformed answer -> LN_EPROTOCOL (connection closed); an ERROR
 * whose code is not in the table -> LN_EPROTOCOL (well-formed, so the connection stays); a
 * body that failed to encode -> its wbuf code (nothing sent).
 * No answer in time -> LN_ETIMEOUT: if no byte of the answer had arrived the connection is
 * kept and the late answer is skipped by a later request (a late PORT_OK is released with a
 * CLOSE_PORT), otherwise the connection is closed as for a lost connection. */
int ln_client_request(ln_client* clnt, uint16_t type, const ln_wbuf* body, uint16_t* reply_type,
                      ln_rbuf* reply);

/* What the client does with a port (or service provider) it holds. */
typedef struct ln_client_port_ops {
    /* ln_client_destroy calls it for each remaining port (newest first) before
     * disconnecting; it must call ln_client_remove_port itself. */
    void (*close)(void* port);
    /* Registers the port again on a new manager connection: called with the ports lock and
     * the request lock held, by the reconnect monitor or ln_client_settle_port; sends with
     * ln_client_request_locked.  A refusal is recorded for that port and returned. */
    int (*reclaim)(ln_client* clnt, void* port);
} ln_client_port_ops;

/* Ports registered on the client, for ln_client_destroy and for re-registration after a
 * reconnect.  add: LN_OK or LN_ENOMEM (recorded); `gen` is the connection its registration
 * was made on (ln_client_request_gen): if the client reconnected since, the port is
 * re-registered at once.  remove waits for a re-registration in progress, so that afterwards
 * nothing but the caller touches the port. */
int ln_client_add_port(ln_client* clnt, void* port, const ln_client_port_ops* ops, uint64_t gen);
void ln_client_remove_port(ln_client* clnt, void* port);
/* For registration data that changes after add (a provider that registers later): take the
 * ports lock around the change, then settle with the connection the registration went out
 * on (re-registering it if that connection is gone and a new one is up). */
void ln_client_lock_ports(ln_client* clnt);
void ln_client_unlock_ports(ln_client* clnt);
void ln_client_settle_port(ln_client* clnt, void* port, uint64_t gen); /* unlocks */
/* The connection the calling thread's last successful ln_client_request went out on. */
uint64_t ln_client_request_gen(void);
/* ln_client_request for reclaim callbacks, which already hold the request lock. */
int ln_client_request_locked(ln_client* clnt, uint16_t type, const ln_wbuf* body,
                             uint16_t* reply_type, ln_rbuf* reply);
pid_t ln_client_pid(const ln_client* clnt);
/* The instance name from the manager's WELCOME (owned by the client). */
const char* ln_client_instance(const ln_client* clnt);
/* The numeric local address of the manager connection (the interface that reaches the
 * manager), e.g. "192.168.1.5".  LN_OK, or LN_ECONNECTION (recorded) when disconnected. */
int ln_client_local_host(ln_client* clnt, char* out, size_t size);

/* The session key of the current manager connection (docs/security.md, "Client admission to
 * the manager"): LN_OK with it in `out`, LN_ENOTFOUND if that connection was admitted without
 * the client key.  Each connection (a reconnect too) has its own. */
int ln_client_session_key(ln_client* clnt, uint8_t out[32]);

/* For lasterror.c: copy an already formatted error into the client. */
void ln_client_store_error(ln_client* clnt, int code, const char* text);

#endif /* LN_CLIENT_INTERNAL_H */
