/* svc_internal.h — the provider side of services inside libln: providers, the endpoints (listening
 * sockets and caller connections) they own, the groups whose epoll sets hold those endpoints,
 * and the thread pools that serve groups.  provider.c owns providers and requests,
 * svc_group.c groups, event dispatch and pools.  Never installed.
 *
 * Concurrency: every endpoint is armed EPOLLONESHOT, so at most one thread handles it at a time.
 * Handling an event holds the group's `life` lock shared; removing a provider holds it
 * exclusively, so no handler of the group runs while endpoints are freed.  Events carry an
 * (index, generation) key, never a pointer: a thread that took an event for an endpoint that
 * was freed meanwhile finds the generation changed and drops the event. */
#ifndef LN_SVC_INTERNAL_H
#define LN_SVC_INTERNAL_H

#include <pthread.h>
#include <stdatomic.h>
#include <stdint.h>

#include "arena.h"
#include "client_internal.h"
#include "sigcodec.h"
#include "svc_secure.h"
#include "svc_tap.h"
#include "svc_wire.h"

#define LN_SVC_MAX_NAME 255
#define LN_SVC_MAX_POOL_THREADS 256

typedef struct ln_svc_group ln_svc_group;
typedef struct ln_svc_pool ln_svc_pool;

enum ln_svc_ep_kind { LN_SVC_EP_LISTEN, LN_SVC_EP_CONN };

typedef struct ln_svc_endpoint {
    enum ln_svc_ep_kind kind;
    int fd;
    uint32_t index; /* slot in the group's table */
    ln_service_provider* prov;
    int tcp; /* a TCP listener, or a connection it accepted: protected (svc_secure.h) */
    /* connections only */
    int greeted; /* the caller's HELLO was accepted */
    int broken;  /* a send failed: close after this event */
    uint8_t* rx;
    size_t rx_len, rx_cap;
    ln_wbuf tx;
    ln_arena arena;
    void* request;                    /* decoded request struct, prov->request_size bytes */
    char caller[LN_SVC_MAX_NAME + 1]; /* the caller's client name from HELLO ("" if none) */
    int64_t tap_id;                   /* > 0: a recorder's connection (svc_tap.h) */
    int first_done;                   /* TCP: the first frame (SECURE or not) was taken */
    ln_svc_channel ch;                /* TCP with security: the keys; level NONE: plain */
} ln_svc_endpoint;

struct ln_service_provider {
    uint32_t magic;
    ln_client* clnt;
    char name[LN_SVC_MAX_NAME + 1];
    char md_name[LN_SVC_MAX_NAME + 1];
    uint64_t layout_hash;
    char* signature;
    ln_sig* req_sig;
    ln_sig* resp_sig;
    size_t request_size, response_size;
    size_t max_size;
    ln_service_handler handler;
    void* user_data;

    ln_svc_group* group; /* NULL until registered (set under the client's ports lock) */
    char unix_path[108];
    uint16_t tcp_port;
    char group_name[LN_SVC_MAX_NAME + 1]; /* as registered, for re-registering */
    char tcp_host[256];
    atomic_uint_fast64_t calls, errors, reported_calls;
    atomic_int_fast64_t last_report_ns; /* CLOCK_MONOTONIC of the last SERVICE_CALLED */
    atomic_flag reporting;
    atomic_int tapped; /* recorders tapping the calls: the call path's only check */
    ln_svc_taps* taps; /* svc_tap.c: their queues and sender thread */
};

struct ln_service_request {
    ln_service_provider* prov;
    ln_svc_endpoint* ep;
    uint32_t call_id;
    int answered; /* 0, or the LN_E* code of a failed answer, or 1 */
    int failed;   /* answered with an error */
    /* for recorders, set only while tapped: the request's wire form and when it arrived */
    const uint8_t* wire;
    size_t wire_len;
    int64_t t_real_ns, t_mono_ns;
};

/* ---- svc_group.c ---- */
/* The group `name` (NULL or "" for the default one) of the client in *out, created if `create`.
 * LN_OK, LN_ENOTFOUND if it does not exist (and !create), LN_EINVAL, LN_ENOMEM (recorded). */
int ln_svc_group_get(ln_client* clnt, const char* name, int create, ln_svc_group** out);
/* Adds a listening socket of `prov` to its group and arms it (`tcp`: its connections are
 * protected as svc_secure.h says).  LN_OK or an error (recorded). */
int ln_svc_group_add_listener(ln_svc_group* g, ln_service_provider* prov, int fd, int tcp);
/* Removes every endpoint of `prov` from its group (waits for running handlers of the group).
 * LN_EBUSY if called from a handler of that group. */
int ln_svc_group_remove_provider(ln_svc_group* g, ln_service_provider* prov);
/* Stops every pool of the client (called by ln_client_destroy before ports close), and frees
 * the groups afterwards. */
void ln_svc_client_stop_pools(ln_client* clnt);
void ln_svc_client_free(ln_client* clnt);

/* ---- provider.c ---- */
/* Handles what arrived on connection `ep`.  Returns the number of requests answered (>= 0), or
 * -1 if the connection must be closed. */
int ln_svc_conn_readable(ln_svc_endpoint* ep);
void ln_svc_endpoint_free(ln_svc_endpoint* ep);
/* Sends the provider's call counts to the manager if they changed and (unless `force`) the
 * last report is at least a second old. */
void ln_svc_report_calls(ln_service_provider* p, int force);
/* Argument checks shared by callers and providers (recorded errors, `what` names the call). */
int ln_svc_check_names(ln_client* clnt, const char* what, const char* name, const char* md_name,
                       const char* signature);
/* Splits and parses a service signature "request|response"; LN_EMD names the md. */
int ln_svc_parse_signature(ln_client* clnt, const char* md_name, const char* signature,
                           ln_sig** req, ln_sig** resp);

/* ---- service.c: one call in two halves, so that events (event_call.c) send a call to every
 * handler before waiting for any answer.  The caller owns the handle exclusively (no other
 * thread calls on it); receive only after a send that returned LN_OK.  Errors as for
 * ln_service_call (recorded); deadline NULL waits forever. ---- */
struct timespec;
int ln_svc_call_send(ln_service* s, const void* request, const struct timespec* deadline);
int ln_svc_call_receive(ln_service* s, void* response, const struct timespec* deadline);

#endif /* LN_SVC_INTERNAL_H */
