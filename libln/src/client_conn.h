/* client_conn.h — the inside of a client handle, shared by client.c (handle, ports, options,
 * create/destroy) and client_conn.c (the manager connection: handshake and requests).
 * Nothing else in libln may include it: the rest uses client_internal.h. */
#ifndef LN_CLIENT_CONN_H
#define LN_CLIENT_CONN_H

#include "client_internal.h"

#define LN_CLIENT_MAX_ADDRESS 255 /* bytes of "HOST:PORT" */

struct ln_client_port {
    void* port;
    void (*close_fn)(void* port);
};

struct ln_client {
    uint32_t magic;
    pid_t pid;
    double timeout; /* seconds, < 0: wait forever */
    uint32_t client_id;
    char address[LN_CLIENT_MAX_ADDRESS + 3]; /* "host:port" for texts, IPv6 hosts in [] */
    char name[LN_PROTO_MAX_STR + 1];         /* as assigned by the manager */
    char instance[LN_PROTO_MAX_STR + 1];

    pthread_mutex_t request_lock; /* one round trip at a time; guards the fields up to rx_cap */
    int fd;                       /* -1 once the connection is gone */
    uint32_t last_request_id;
    uint32_t stale_answers; /* answers still due to requests that timed out */
    ln_wbuf tx;
    uint8_t* rx;
    size_t rx_cap;

    pthread_mutex_t state_lock; /* guards ports and the last error */
    struct ln_client_port* ports;
    size_t nports, ports_cap;
    int last_code;
    char last_error[LN_ERROR_TEXT_MAX];

    struct ln_svc_state* svc; /* service groups and pools (svc_group.c), created on first use */
};

/* Connects to host:port, sends HELLO as `name` and takes the WELCOME (client_id, name,
 * instance).  `from` says where the address came from, for error texts (may be "").  On
 * failure the reason is recorded and the connection is closed. */
int ln_conn_open(ln_client* c, const char* host, const char* port, const char* from,
                 const char* name);
/* Closes the connection (if still open) and frees its buffers. */
void ln_conn_close(ln_client* c);

#endif /* LN_CLIENT_CONN_H */
