/* client_conn.h — the inside of a client handle, shared by client.c (handle, ports, options,
 * create/destroy), client_conn.c (the manager connection: handshake and requests) and
 * client_log.c (the log queue).  Nothing else in libln may include it: the rest uses
 * client_internal.h. */
#ifndef LN_CLIENT_CONN_H
#define LN_CLIENT_CONN_H

#include "client_internal.h"

#define LN_CLIENT_MAX_ADDRESS 255 /* bytes of "HOST:PORT" */

/* One TCP connection to a manager and its request state. */
struct ln_conn {
    int fd;     /* -1 if none; with a monitor only the monitor closes the client's */
    int usable; /* connected and registered: requests may go out */
    int broken; /* it failed: nothing more goes out on it */
    uint32_t last_request_id;
    uint32_t stale_answers; /* answers still due to requests that timed out */
    ln_wbuf tx;
    uint8_t* rx;
    size_t rx_cap;
    /* Derived by admission by key (client_auth.h), for sealing what the manager hands out;
     * none after admission by credentials. */
    int has_session_key;
    uint8_t session_key[32];
};

struct ln_client_port {
    void* port;
    const ln_client_port_ops* ops;
};

struct ln_client {
    uint32_t magic;
    pid_t pid;
    double timeout;                          /* seconds, < 0: wait forever */
    char address[LN_CLIENT_MAX_ADDRESS + 3]; /* "host:port" for texts, IPv6 hosts in [] */
    char host[LN_CLIENT_MAX_ADDRESS + 1];    /* what to connect to again */
    char port[6];
    char name[LN_PROTO_MAX_STR + 1]; /* as assigned by the manager at creation */
    char instance[LN_PROTO_MAX_STR + 1];

    /* Lock order: ports_lock, then request_lock, then state_lock; none is taken by
     * ln_write/ln_read (state_lock only when they fail, to record the error). */
    pthread_mutex_t ports_lock; /* the ports list and the ports' registration data */
    struct ln_client_port* ports;
    size_t nports, ports_cap;

    pthread_mutex_t request_lock; /* one round trip at a time; guards client_id to conn_gen */
    uint32_t client_id;
    struct ln_conn conn; /* the connection requests use */
    uint64_t conn_gen;   /* counts connections that became usable */
    /* While the monitor re-registers ports (under the ports lock) on a connection that is not
     * yet `conn`, the reclaim callbacks' requests go there. */
    struct ln_conn* reclaim_conn;

    pthread_mutex_t state_lock; /* guards the last error */
    int last_code;
    char last_error[LN_ERROR_TEXT_MAX];

    /* The reconnect monitor (client_conn.c); cancel_fd is an eventfd that destroy signals
     * to end it, also in the middle of a connect or a re-registration. */
    int monitored;
    int cancel_fd;
    pthread_t monitor;

    struct ln_svc_state* svc; /* service groups and pools (svc_group.c), created on first use */
    /* The service key the manager gave last (svc_key.c), under state_lock; wiped by destroy. */
    int svc_key_known;
    int svc_key_level;
    uint8_t svc_key[32];

    struct ln_replay_clock* _Atomic clock; /* what ln_now follows (clock.c); NULL: realtime */

    struct ln_log_queue* _Atomic log; /* ln_log's queue and sender (client_log.c), on first use */
};

/* Connects to c->host:c->port, sends HELLO as `name` and takes the WELCOME (client_id, name,
 * instance).  `from` says where the address came from, for error texts (may be "").  On
 * failure the reason is recorded and the connection is closed. */
int ln_conn_open(ln_client* c, const char* from, const char* name);
/* Starts the monitor thread that reconnects after a lost connection (ln_client_create, unless
 * reconnection is off).  LN_OK or LN_ESYS/LN_ENOMEM (recorded). */
int ln_conn_start_monitor(ln_client* c);
/* Stops and joins the monitor, wherever it is (ln_client_destroy, before closing ports). */
void ln_conn_stop_monitor(ln_client* c);
/* Sends what ln_log queued and ends the log sender thread (ln_client_destroy, first). */
void ln_log_stop(ln_client* c);
/* Closes the connection (if still open) and frees its buffers. */
void ln_conn_close(ln_client* c);

#endif /* LN_CLIENT_CONN_H */
