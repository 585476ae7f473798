/* provider.c — the provider side of services: creating and registering a provider (its
 * listening sockets and its entry in the manager, again after a reconnect), reading requests
 * from caller connections, running the handler and sending its answer, and reporting call
 * counts to the manager. */
#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include <sodium.h>

#include "naming.h"
#include "net.h"
#include "svc_internal.h"
#include "waitset_internal.h"

#define LN_PROVIDER_MAGIC 0x4c4e5350u
#define RX_INITIAL 4096
#define RX_KEEP ((size_t)1 << 20) /* an idle connection keeps at most this much buffer */
#define REPORT_INTERVAL_NS 1000000000LL

static atomic_uint socket_counter;

static int provider_check(const ln_service_provider* p)
{
    if (p == NULL || p->magic != LN_PROVIDER_MAGIC)
        return ln_set_error(NULL, LN_EBADHANDLE, "invalid service provider handle");
    return LN_OK;
}

static int64_t clock_ns(clockid_t clock)
{
    struct timespec ts;
    clock_gettime(clock, &ts);
    return (int64_t)ts.tv_sec * 1000000000LL + ts.tv_nsec;
}

static int64_t now_ns(void) { return clock_ns(CLOCK_MONOTONIC); }

/* ---- creating ---- */

static void provider_free(ln_service_provider* p)
{
    ln_svc_taps_free(p);
    ln_sig_free(p->req_sig);
    ln_sig_free(p->resp_sig);
    free(p->signature);
    p->magic = 0;
    free(p);
}

/* Parses "request|response" into both sigs.  LN_OK or LN_EMD (recorded, with the md name). */
int ln_svc_parse_signature(ln_client* clnt, const char* md_name, const char* signature,
                           ln_sig** req, ln_sig** resp)
{
    char *a = NULL, *b = NULL;
    *req = *resp = NULL;
    int rc = ln_sig_split(signature, &a, &b);
    if (rc == LN_OK && (rc = ln_sig_parse(a, req)) != LN_OK)
        rc = ln_set_error(clnt, rc, "service md \"%s\": request signature: %s", md_name,
                          ln_last_error());
    if (rc == LN_OK && (rc = ln_sig_parse(b, resp)) != LN_OK)
        rc = ln_set_error(clnt, rc, "service md \"%s\": response signature: %s", md_name,
                          ln_last_error());
    if (rc == LN_EMD && a == NULL)
        rc = ln_set_error(clnt, rc, "service md \"%s\": %s", md_name, ln_last_error());
    free(a);
    free(b);
    if (rc != LN_OK) {
        ln_sig_free(*req);
        ln_sig_free(*resp);
        *req = *resp = NULL;
    }
    return rc;
}

/* Shared argument checks of ln_get_service and ln_get_service_provider. */
int ln_svc_check_names(ln_client* clnt, const char* what, const char* name, const char* md_name,
                       const char* signature)
{
    if (name == NULL || md_name == NULL || signature == NULL)
        return ln_set_error(clnt, LN_EINVAL, "%s: name, md name and signature are required", what);
    if (name[0] == '\0' || strlen(name) > LN_SVC_MAX_NAME)
        return ln_set_error(clnt, LN_EINVAL, "%s: service name must be 1..%d bytes", what,
                            LN_SVC_MAX_NAME);
    if (md_name[0] == '\0' || strlen(md_name) > LN_SVC_MAX_NAME)
        return ln_set_error(clnt, LN_EINVAL, "%s: md name must be 1..%d bytes", what,
                            LN_SVC_MAX_NAME);
    return LN_OK;
}

static void provider_close_fn(void* p) { ln_unregister_service_provider(p); }

/* Its REGISTER_SERVICE body: every field but the request id. */
static void registration(const ln_service_provider* p, ln_wbuf* body)
{
    char host_id[LN_HOST_ID_MAX];
    ln_host_id(host_id, sizeof host_id);
    ln_msg_register_service m = {.name = ln_strv_of(p->name),
                                 .md_name = ln_strv_of(p->md_name),
                                 .layout_hash = p->layout_hash,
                                 .signature = ln_strv_of(p->signature),
                                 .group = ln_strv_of(p->group_name),
                                 .host_id = ln_strv_of(host_id),
                                 .unix_path = ln_strv_of(p->unix_path),
                                 .tcp_host = ln_strv_of(p->tcp_port ? p->tcp_host : ""),
                                 .tcp_port = p->tcp_port};
    ln_msg_register_service_write_after_id(body, &m);
}

/* After a reconnect (ports and request locks held): register the same sockets again, which
 * callers may still be connected to.  The new manager kept the socket files meanwhile. */
static int reclaim_provider(ln_client* clnt, void* provider)
{
    ln_service_provider* p = provider;
    if (p->group == NULL)
        return LN_OK; /* not registered */
    ln_wbuf body;
    ln_wbuf_init(&body);
    registration(p, &body);
    uint16_t reply_type;
    ln_rbuf reply;
    int rc = ln_client_request_locked(clnt, LN_MSG_REGISTER_SERVICE, &body, &reply_type, &reply);
    ln_wbuf_free(&body);
    if (rc != LN_OK)
        return ln_set_error(clnt, rc,
                            "service \"%s\": the manager refused to take back its "
                            "registration (callers that are connected keep being served): %s",
                            p->name, ln_last_error());
    return LN_OK;
}

static const ln_client_port_ops provider_ops = {provider_close_fn, reclaim_provider};

int ln_get_service_provider(ln_client* clnt, ln_service_provider** out, const char* name,
                            const char* md_name, uint64_t layout_hash, const char* signature)
{
    int rc = ln_client_check(clnt);
    if (rc != LN_OK)
        return rc;
    if (out == NULL)
        return ln_set_error(clnt, LN_EINVAL, "ln_get_service_provider: out must not be NULL");
    *out = NULL;
    rc = ln_svc_check_names(clnt, "ln_get_service_provider", name, md_name, signature);
    if (rc != LN_OK)
        return rc;
    ln_service_provider* p = calloc(1, sizeof *p);
    if (p == NULL || (p->signature = strdup(signature)) == NULL) {
        free(p);
        return ln_set_error(clnt, LN_ENOMEM, "out of memory for service provider \"%s\"", name);
    }
    p->clnt = clnt;
    snprintf(p->name, sizeof p->name, "%s", name);
    snprintf(p->md_name, sizeof p->md_name, "%s", md_name);
    p->layout_hash = layout_hash;
    p->max_size = LN_SERVICE_DEFAULT_MAX_SIZE;
    atomic_flag_clear(&p->reporting);
    if ((p->taps = ln_svc_taps_new()) == NULL) {
        provider_free(p);
        return ln_set_error(clnt, LN_ENOMEM, "out of memory for service provider \"%s\"", name);
    }
    rc = ln_svc_parse_signature(clnt, md_name, signature, &p->req_sig, &p->resp_sig);
    if (rc == LN_OK) {
        p->request_size = ln_sig_size(p->req_sig);
        p->response_size = ln_sig_size(p->resp_sig);
        p->magic = LN_PROVIDER_MAGIC;
        rc = ln_client_add_port(clnt, p, &provider_ops, 0);
    }
    if (rc != LN_OK) {
        provider_free(p);
        return rc;
    }
    *out = p;
    return LN_OK;
}

int ln_service_provider_set_handler(ln_service_provider* p, ln_service_handler handler,
                                    void* user_data)
{
    int rc = provider_check(p);
    if (rc != LN_OK)
        return rc;
    if (handler == NULL)
        return ln_set_error(p->clnt, LN_EINVAL, "service \"%s\": handler must not be NULL",
                            p->name);
    if (p->group != NULL)
        return ln_set_error(p->clnt, LN_EBUSY, "service \"%s\": set the handler before registering",
                            p->name);
    p->handler = handler;
    p->user_data = user_data;
    return LN_OK;
}

int ln_service_provider_set_max_size(ln_service_provider* p, size_t max_bytes)
{
    int rc = provider_check(p);
    if (rc != LN_OK)
        return rc;
    if (max_bytes == 0 || max_bytes > ((size_t)1 << 31))
        return ln_set_error(p->clnt, LN_EINVAL, "service \"%s\": max size %zu is not in 1..2^31",
                            p->name, max_bytes);
    if (p->group != NULL)
        return ln_set_error(p->clnt, LN_EBUSY,
                            "service \"%s\": set the max size before registering", p->name);
    p->max_size = max_bytes;
    return LN_OK;
}

/* ---- registering ---- */

/* Opens the Unix listener (best effort: a caller can still use TCP) and the TCP listener. */
static int open_listeners(ln_service_provider* p, int* ufd, int* tfd, char* host, size_t hsize)
{
    *ufd = *tfd = -1;
    char dir[512];
    if (ln_svc_socket_dir(ln_client_instance(p->clnt), dir, sizeof dir) == LN_OK) {
        if (ln_name_service_socket(dir, (long)getpid(), atomic_fetch_add(&socket_counter, 1) + 1,
                                   p->unix_path, sizeof p->unix_path) != LN_OK ||
            ln_svc_listen_unix(p->unix_path, ufd) != 0)
            p->unix_path[0] = '\0';
    }
    int err = ln_svc_listen_tcp(tfd, &p->tcp_port);
    if (err != 0) {
        *tfd = -1;
        p->tcp_port = 0;
        if (*ufd < 0)
            return ln_set_errno_error(p->clnt, err, "service \"%s\": cannot listen on TCP",
                                      p->name);
    }
    const char* env = getenv("LN_SERVICE_HOST");
    host[0] = '\0';
    if (env != NULL && *env != '\0')
        snprintf(host, hsize, "%s", env);
    else if (*tfd >= 0 && ln_client_local_host(p->clnt, host, hsize) != LN_OK)
        return LN_ECONNECTION;
    return LN_OK;
}

static void close_listeners(ln_service_provider* p, int ufd, int tfd)
{
    if (ufd >= 0) {
        close(ufd);
        unlink(p->unix_path);
    }
    if (tfd >= 0)
        close(tfd);
    p->unix_path[0] = '\0';
    p->tcp_port = 0;
}

int ln_service_provider_register(ln_service_provider* p, const char* group)
{
    int rc = provider_check(p);
    if (rc != LN_OK)
        return rc;
    if (p->group != NULL)
        return ln_set_error(p->clnt, LN_EBUSY, "service \"%s\" is already registered", p->name);
    if (p->handler == NULL)
        return ln_set_error(p->clnt, LN_EINVAL, "service \"%s\": set a handler first", p->name);
    ln_svc_group* g;
    rc = ln_svc_group_get(p->clnt, group, 1, &g);
    if (rc != LN_OK)
        return rc;
    int ufd, tfd;
    char host[256];
    rc = open_listeners(p, &ufd, &tfd, host, sizeof host);
    if (rc != LN_OK) {
        close_listeners(p, ufd, tfd);
        return rc;
    }
    snprintf(p->group_name, sizeof p->group_name, "%s", group ? group : "");
    snprintf(p->tcp_host, sizeof p->tcp_host, "%s", tfd >= 0 ? host : "");

    ln_wbuf body;
    ln_wbuf_init(&body);
    registration(p, &body);
    uint16_t reply_type;
    ln_rbuf reply;
    rc = ln_client_request(p->clnt, LN_MSG_REGISTER_SERVICE, &body, &reply_type, &reply);
    uint64_t gen = ln_client_request_gen();
    ln_wbuf_free(&body);
    if (rc != LN_OK) {
        close_listeners(p, ufd, tfd);
        return ln_set_error(p->clnt, rc, "cannot register service \"%s\": %s", p->name,
                            ln_last_error());
    }
    /* Listen only once the manager took it, so a refused registration leaves nothing.  From
     * here on a reconnect re-registers it (at once, if one happened since the request). */
    ln_client_lock_ports(p->clnt);
    p->group = g;
    ln_client_settle_port(p->clnt, p, gen);
    if ((ufd >= 0 && (rc = ln_svc_group_add_listener(g, p, ufd, 0)) != LN_OK) ||
        (tfd >= 0 && (rc = ln_svc_group_add_listener(g, p, tfd, 1)) != LN_OK)) {
        ln_svc_group_remove_provider(g, p); /* closes what was added */
        ln_client_lock_ports(p->clnt);
        p->group = NULL;
        ln_client_unlock_ports(p->clnt);
        return rc;
    }
    return LN_OK;
}

int ln_unregister_service_provider(ln_service_provider* p)
{
    int rc = provider_check(p);
    if (rc != LN_OK)
        return rc;
    if (p->group != NULL) {
        rc = ln_svc_group_remove_provider(p->group, p);
        if (rc != LN_OK)
            return rc;
        /* Off the client before unregistering: a re-registration in progress ends first,
         * and none comes after the UNREGISTER. */
        ln_client_remove_port(p->clnt, p);
        ln_wbuf body;
        ln_wbuf_init(&body);
        ln_msg_unregister_service m = {.name = ln_strv_of(p->name)};
        ln_msg_unregister_service_write_after_id(&body, &m);
        uint16_t reply_type;
        ln_rbuf reply;
        /* A lost manager connection forgets the service anyway. */
        ln_client_request(p->clnt, LN_MSG_UNREGISTER_SERVICE, &body, &reply_type, &reply);
        ln_wbuf_free(&body);
        if (p->unix_path[0] != '\0')
            unlink(p->unix_path);
    }
    ln_client_remove_port(p->clnt, p);
    provider_free(p);
    return LN_OK;
}

/* ---- counts ---- */

void ln_svc_report_calls(ln_service_provider* p, int force)
{
    int64_t now = now_ns();
    if (!force && now - atomic_load(&p->last_report_ns) < REPORT_INTERVAL_NS)
        return;
    if (atomic_flag_test_and_set(&p->reporting))
        return;
    uint64_t calls = atomic_load(&p->calls), errors = atomic_load(&p->errors);
    if (calls != atomic_load(&p->reported_calls)) {
        atomic_store(&p->last_report_ns, now);
        atomic_store(&p->reported_calls, calls);
        ln_wbuf body;
        ln_wbuf_init(&body);
        ln_msg_service_called m = {.name = ln_strv_of(p->name), .calls = calls, .errors = errors};
        ln_msg_service_called_write_after_id(&body, &m);
        uint16_t reply_type;
        ln_rbuf reply;
        ln_client_request(p->clnt, LN_MSG_SERVICE_CALLED, &body, &reply_type, &reply);
        ln_wbuf_free(&body);
    }
    atomic_flag_clear(&p->reporting);
}

/* ---- one connection ---- */

void ln_svc_endpoint_free(ln_svc_endpoint* ep)
{
    if (ep == NULL)
        return;
    if (ep->tap_id > 0)
        ln_svc_tap_hangup(ep->prov, ep->tap_id);
    close(ep->fd);
    ln_svc_channel_wipe(&ep->ch);
    free(ep->rx);
    ln_wbuf_free(&ep->tx);
    ln_arena_free(&ep->arena);
    free(ep->request);
    free(ep);
}

/* Sends ep->tx.  LN_OK, or -1 after which the connection is closed. */
static int send_tx(ln_svc_endpoint* ep)
{
    struct timespec ts;
    if (ep->tx.failed)
        return -1;
    if (ep->ch.level != LN_SVC_SEC_NONE && ln_svc_seal(&ep->ch, &ep->tx, 0) != LN_OK) {
        ln_wbuf_reset(&ep->tx);
        ep->broken = 1;
        return -1;
    }
    int err = ln_net_write_all(ep->fd, ep->tx.data, ep->tx.len,
                               ln_net_deadline(&ts, LN_SVC_SEND_TIMEOUT), -1);
    ln_wbuf_reset(&ep->tx);
    if (err != 0)
        ep->broken = 1;
    return err ? -1 : LN_OK;
}

static void send_error(ln_svc_endpoint* ep, uint32_t call_id, int code, const char* fmt, ...)
    __attribute__((format(printf, 4, 5)));
static void send_error(ln_svc_endpoint* ep, uint32_t call_id, int code, const char* fmt, ...)
{
    char text[LN_SVC_MAX_ERROR_TEXT + 1];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    ln_wbuf_reset(&ep->tx);
    ln_svc_put_error(&ep->tx, call_id, code, text);
    send_tx(ep);
}

static int answer_error(ln_service_request* req, int code, const char* text)
{
    ln_service_provider* p = req->prov;
    send_error(req->ep, req->call_id, code, "%s", text);
    req->answered = 1;
    req->failed = 1;
    atomic_fetch_add(&p->errors, 1);
    if (atomic_load_explicit(&p->tapped, memory_order_relaxed))
        ln_svc_tap_call(p, req, code, text, strlen(text));
    return req->ep->broken ? LN_ECONNECTION : LN_OK;
}

/* The checks a HELLO and a TAP share: a whole frame with our magic, our protocol version and
 * this socket's service; else an ERROR to the peer (`malformed` says which frame) and -1. */
static int check_greeting(ln_svc_endpoint* ep, ln_rbuf* r, uint32_t magic, uint16_t version,
                          const char* name, const char* malformed)
{
    ln_service_provider* p = ep->prov;
    if (ln_rbuf_end(r) != LN_OK || magic != LN_SVC_MAGIC) {
        send_error(ep, 0, LN_EPROTOCOL, "service \"%s\": %s", p->name, malformed);
        return -1;
    }
    if (version != LN_SVC_VERSION) {
        send_error(ep, 0, LN_EVERSION, "service \"%s\" speaks service protocol %d, not %u", p->name,
                   LN_SVC_VERSION, version);
        return -1;
    }
    if (strcmp(name, p->name) != 0) {
        send_error(ep, 0, LN_ENOTFOUND, "this socket serves service \"%s\", not \"%s\"", p->name,
                   name);
        return -1;
    }
    return 0;
}

static int handle_hello(ln_svc_endpoint* ep, ln_rbuf* r)
{
    ln_service_provider* p = ep->prov;
    char name[LN_PROTO_MAX_STR + 1];
    uint32_t magic = ln_rbuf_u32(r);
    uint16_t version = ln_rbuf_u16(r);
    ln_rbuf_str(r, name, sizeof name);
    uint64_t hash = ln_rbuf_u64(r);
    if (r->left > 0 && !r->failed) { /* the caller's name, sent since recording calls */
        char caller[LN_PROTO_MAX_STR + 1];
        ln_rbuf_str(r, caller, sizeof caller);
        size_t n = strnlen(caller, sizeof ep->caller - 1); /* cut: names are short */
        while (n > 0 && !ln_utf8_valid(caller, n))
            n--; /* at a character boundary */
        memcpy(ep->caller, caller, n);
        ep->caller[n] = '\0';
    }
    if (check_greeting(ep, r, magic, version, name, "expected a HELLO frame") < 0)
        return -1;
    if (hash != p->layout_hash) {
        send_error(ep, 0, LN_ELAYOUT,
                   "service \"%s\" has md \"%s\" with layout 0x%016llx, the caller's layout is "
                   "0x%016llx",
                   p->name, p->md_name, (unsigned long long)p->layout_hash,
                   (unsigned long long)hash);
        return -1;
    }
    ep->greeted = 1;
    ln_wbuf_reset(&ep->tx);
    size_t start = ln_proto_frame_begin(&ep->tx, LN_SVC_WELCOME);
    ln_svc_frame_end(&ep->tx, start);
    return send_tx(ep);
}

/* A recorder's TAP: answer TAPPED and hand a duplicate of the socket to the tap's sender; the
 * endpoint stays in the group only to notice the recorder hanging up. */
static int handle_tap(ln_svc_endpoint* ep, ln_rbuf* r)
{
    ln_service_provider* p = ep->prov;
    char name[LN_PROTO_MAX_STR + 1], recorder[LN_PROTO_MAX_STR + 1];
    uint32_t magic = ln_rbuf_u32(r);
    uint16_t version = ln_rbuf_u16(r);
    ln_rbuf_str(r, name, sizeof name);
    ln_rbuf_str(r, recorder, sizeof recorder);
    if (check_greeting(ep, r, magic, version, name, "malformed TAP frame") < 0)
        return -1;
    ln_wbuf_reset(&ep->tx);
    size_t start = ln_proto_frame_begin(&ep->tx, LN_SVC_TAPPED);
    ln_wbuf_str(&ep->tx, p->md_name);
    ln_wbuf_u64(&ep->tx, p->layout_hash);
    const char* provider = ln_client_name(p->clnt);
    ln_wbuf_str(&ep->tx, provider ? provider : "");
    ln_wbuf_str(&ep->tx, p->signature);
    if (ln_svc_frame_end(&ep->tx, start) != LN_OK || send_tx(ep) != LN_OK)
        return -1;
    int fd = dup(ep->fd);
    if (fd < 0)
        return -1;
    int64_t id = ln_svc_tap_add(p, fd);
    if (id < 0)
        return -1;
    ep->tap_id = id;
    return LN_OK;
}

static int handle_request(ln_svc_endpoint* ep, ln_rbuf* r)
{
    ln_service_provider* p = ep->prov;
    uint32_t call_id = ln_rbuf_u32(r);
    if (r->failed) {
        send_error(ep, 0, LN_EPROTOCOL, "service \"%s\": REQUEST frame without a call id", p->name);
        return -1;
    }
    ln_service_request req = {.prov = p, .ep = ep, .call_id = call_id};
    if (atomic_load_explicit(&p->tapped, memory_order_relaxed)) {
        req.wire = r->p;
        req.wire_len = r->left;
        req.t_real_ns = clock_ns(CLOCK_REALTIME);
        req.t_mono_ns = now_ns();
    }
    atomic_fetch_add(&p->calls, 1);
    if (ep->request == NULL && (ep->request = calloc(1, p->request_size + 1)) == NULL) {
        answer_error(&req, LN_ENOMEM, "provider is out of memory");
        return ep->broken ? -1 : 1;
    }
    ln_arena_reset(&ep->arena);
    int rc = ln_sig_decode(p->req_sig, r->p, r->left, ep->request, &ep->arena, p->max_size);
    if (rc != LN_OK) {
        char text[LN_SVC_MAX_ERROR_TEXT];
        snprintf(text, sizeof text, "service \"%s\" refused a malformed request: %s", p->name,
                 ln_last_error());
        answer_error(&req, rc, text);
        return ep->broken ? -1 : 1;
    }
    ln_set_error(NULL, LN_OK, "%s", ""); /* so a handler error names its own cause */
    rc = p->handler(p->clnt, &req, p->user_data);
    if (!req.answered) {
        char text[LN_SVC_MAX_ERROR_TEXT];
        if (rc < 0)
            snprintf(text, sizeof text, "handler of service \"%s\" failed: %s%s%s", p->name,
                     ln_strerror(rc), ln_last_error()[0] ? ": " : "", ln_last_error());
        else
            snprintf(text, sizeof text, "handler of service \"%s\" returned without responding",
                     p->name);
        answer_error(&req, LN_ESERVICE, text);
    }
    if (ep->rx_cap > RX_KEEP || ln_arena_held(&ep->arena) > RX_KEEP)
        ln_arena_free(&ep->arena);
    ln_svc_report_calls(p, 0);
    return ep->broken ? -1 : 1;
}

/* ---- protected connections (TCP; svc_secure.h) ---- */

/* A refusal the caller may not be able to authenticate: sent plain, then the connection
 * closes (-1). */
static int refuse_plain(ln_svc_endpoint* ep, int code, const char* fmt, ...)
    __attribute__((format(printf, 3, 4)));
static int refuse_plain(ln_svc_endpoint* ep, int code, const char* fmt, ...)
{
    char text[LN_SVC_MAX_ERROR_TEXT + 1];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    ln_svc_channel_wipe(&ep->ch);
    send_error(ep, 0, code, "%s", text);
    return -1;
}

/* The caller's SECURE: answer SECURED with our nonce and derive the keys.  0 or -1. */
static int handle_secure(ln_svc_endpoint* ep, ln_rbuf* r, const ln_svc_key* key)
{
    ln_service_provider* p = ep->prov;
    char name[LN_PROTO_MAX_STR + 1];
    uint8_t theirs[LN_SVC_NONCE_BYTES], mine[LN_SVC_NONCE_BYTES];
    uint32_t magic = ln_rbuf_u32(r);
    uint16_t version = ln_rbuf_u16(r);
    uint16_t level = ln_rbuf_u16(r);
    unsigned offer = ln_rbuf_u16(r);
    ln_rbuf_str(r, name, sizeof name);
    ln_svc_read_nonce(r, theirs);
    if (check_greeting(ep, r, magic, version, name, "malformed SECURE frame") < 0)
        return -1;
    if (level != key->level)
        return refuse_plain(ep, LN_EPERM,
                            "service \"%s\": the provider's instance has security %s, the "
                            "caller asks for %s",
                            p->name, ln_svc_level_name(key->level), ln_svc_level_name(level));
    int aead = ln_svc_aead_pick(ln_svc_aead_offer(), offer);
    if (aead == 0)
        return refuse_plain(ep, LN_EPERM, "service \"%s\": no AEAD in common with the caller",
                            p->name);
    ln_svc_nonce(mine);
    ln_wbuf_reset(&ep->tx);
    size_t start = ln_proto_frame_begin(&ep->tx, LN_SVC_SECURED);
    ln_wbuf_u16(&ep->tx, level);
    ln_wbuf_u16(&ep->tx, (uint16_t)aead);
    ln_wbuf_bytes(&ep->tx, mine, sizeof mine);
    if (ln_svc_frame_end(&ep->tx, start) != LN_OK || send_tx(ep) != LN_OK)
        return -1;
    return ln_svc_channel_init(&ep->ch, key, aead, theirs, mine, p->name, 0) == LN_OK ? 0 : -1;
}

/* The first frame on a TCP connection: SECURE, or anything else only with security none.
 * 1: it was SECURE (taken), 0: go on with it as a plain frame, -1: close. */
static int first_tcp_frame(ln_svc_endpoint* ep, uint16_t type, ln_rbuf* r)
{
    ln_service_provider* p = ep->prov;
    ln_svc_key key;
    if (ln_svc_key_get(p->clnt, &key) != LN_OK)
        return refuse_plain(ep, LN_ECONNECTION,
                            "service \"%s\": the provider has no service key: %s", p->name,
                            ln_last_error());
    int rc;
    if (type == LN_SVC_SECURE && key.level == LN_SVC_SEC_NONE)
        rc = refuse_plain(ep, LN_EPERM,
                          "service \"%s\": the provider's instance has security none, the "
                          "caller asks for protected calls",
                          p->name);
    else if (type == LN_SVC_SECURE)
        rc = handle_secure(ep, r, &key) < 0 ? -1 : 1;
    else if (key.level == LN_SVC_SEC_NONE)
        rc = 0;
    else
        rc = refuse_plain(
            ep, LN_EPERM, "service \"%s\" takes calls over TCP only protected (security %s)%s",
            p->name, ln_svc_level_name(key.level),
            type == LN_SVC_TAP ? "; record calls on the provider's host instead"
                               : ": the caller asked without (its instance has security none, "
                                 "or its libln is older)");
    sodium_memzero(&key, sizeof key);
    return rc;
}

/* A frame on a protected connection: opened into *type and *r, or -1 (close) after telling
 * the caller.  A frame that fails to open never reaches a handler. */
static int open_sealed(ln_svc_endpoint* ep, uint8_t* frame, size_t len, uint16_t* type, ln_rbuf* r)
{
    ln_service_provider* p = ep->prov;
    uint8_t* body;
    size_t body_len;
    int rc = *type == LN_SVC_SEALED ? ln_svc_open(&ep->ch, frame, len, type, &body, &body_len)
                                    : LN_EPERM;
    if (rc == LN_EPERM) {
        atomic_fetch_add(&p->errors, 1);
        return refuse_plain(ep, LN_EPERM,
                            "service \"%s\": a frame from the caller failed authentication "
                            "(forged, replayed, reordered or cut on the way); connection closed",
                            p->name);
    }
    if (rc != LN_OK) {
        send_error(ep, 0, LN_EPROTOCOL, "service \"%s\": malformed frame inside a sealed frame",
                   p->name);
        return -1;
    }
    ln_rbuf_init(r, body, body_len);
    return 0;
}

int ln_svc_conn_readable(ln_svc_endpoint* ep)
{
    ln_service_provider* p = ep->prov;
    /* Read what is there; a frame bigger than the buffer grows it as its bytes arrive. */
    for (;;) {
        if (ep->rx_len == ep->rx_cap) {
            size_t want = ep->rx_cap ? 2 * ep->rx_cap : RX_INITIAL;
            uint8_t* rx = realloc(ep->rx, want);
            if (rx == NULL)
                return -1;
            ep->rx = rx;
            ep->rx_cap = want;
        }
        ssize_t n = recv(ep->fd, ep->rx + ep->rx_len, ep->rx_cap - ep->rx_len, 0);
        if (n > 0) {
            ep->rx_len += (size_t)n;
            if (ep->rx_len < ep->rx_cap)
                break;
        } else if (n == 0) {
            return -1; /* the caller hung up */
        } else if (errno == EAGAIN || errno == EWOULDBLOCK) {
            break;
        } else if (errno != EINTR) {
            return -1;
        }
    }
    int answered = 0;
    size_t used = 0;
    while (ep->rx_len - used >= LN_SVC_HEADER_SIZE) {
        uint32_t body_len;
        uint16_t type;
        int rc = ln_svc_parse_header(ep->rx + used, p->max_size, &body_len, &type);
        if (rc == LN_ETOOBIG) {
            send_error(ep, 0, LN_ETOOBIG,
                       "service \"%s\": a request frame of %u bytes exceeds the provider's "
                       "maximum of %zu",
                       p->name, (unsigned)body_len, p->max_size);
            atomic_fetch_add(&p->errors, 1);
            return -1;
        }
        if (rc != LN_OK) {
            send_error(ep, 0, LN_EPROTOCOL, "service \"%s\": malformed frame header", p->name);
            return -1;
        }
        if (ep->rx_len - used - LN_SVC_HEADER_SIZE < body_len)
            break;
        ln_rbuf r;
        uint8_t* frame = ep->rx + used;
        used += LN_SVC_HEADER_SIZE + body_len;
        ln_rbuf_init(&r, frame + LN_SVC_HEADER_SIZE, body_len);
        if (ep->ch.level != LN_SVC_SEC_NONE) {
            if (open_sealed(ep, frame, LN_SVC_HEADER_SIZE + body_len, &type, &r) < 0)
                return -1;
        } else if (ep->tcp && !ep->first_done) {
            ep->first_done = 1;
            int first = first_tcp_frame(ep, type, &r);
            if (first < 0)
                return -1;
            if (first > 0)
                continue;
        }
        if (ep->tap_id > 0) {
            return -1; /* a recorder sends nothing after TAP */
        } else if (!ep->greeted && type == LN_SVC_TAP && ep->ch.level == LN_SVC_SEC_NONE) {
            if (handle_tap(ep, &r) < 0)
                return -1;
        } else if (!ep->greeted) {
            if (type != LN_SVC_HELLO) {
                send_error(ep, 0, LN_EPROTOCOL, "service \"%s\": expected a HELLO frame", p->name);
                return -1;
            }
            if (handle_hello(ep, &r) < 0)
                return -1;
        } else if (type == LN_SVC_REQUEST) {
            int n = handle_request(ep, &r);
            if (n < 0)
                return -1;
            answered += n;
        } else {
            send_error(ep, 0, LN_EPROTOCOL, "service \"%s\": unexpected frame type %u", p->name,
                       type);
            return -1;
        }
    }
    memmove(ep->rx, ep->rx + used, ep->rx_len - used);
    ep->rx_len -= used;
    if (ep->rx_len == 0 && ep->rx_cap > RX_KEEP) {
        free(ep->rx);
        ep->rx = NULL;
        ep->rx_cap = 0;
    }
    return answered;
}

/* ---- inside a handler ---- */

static int request_check(const ln_service_request* req)
{
    if (req == NULL || req->prov == NULL)
        return ln_set_error(NULL, LN_EBADHANDLE, "invalid service request handle");
    return LN_OK;
}

int ln_service_request_get_data(ln_service_request* req, void* request)
{
    int rc = request_check(req);
    if (rc != LN_OK)
        return rc;
    if (request == NULL && req->prov->request_size > 0)
        return ln_set_error(req->prov->clnt, LN_EINVAL, "service \"%s\": request buffer is NULL",
                            req->prov->name);
    if (req->prov->request_size > 0)
        memcpy(request, req->ep->request, req->prov->request_size);
    return LN_OK;
}

int ln_service_request_respond(ln_service_request* req, const void* response)
{
    int rc = request_check(req);
    if (rc != LN_OK)
        return rc;
    ln_service_provider* p = req->prov;
    ln_svc_endpoint* ep = req->ep;
    if (req->answered)
        return ln_set_error(p->clnt, LN_EINVAL, "service \"%s\": call already answered", p->name);
    if (response == NULL && p->response_size > 0)
        return ln_set_error(p->clnt, LN_EINVAL, "service \"%s\": response is NULL", p->name);
    ln_wbuf_reset(&ep->tx);
    size_t start = ln_proto_frame_begin(&ep->tx, LN_SVC_RESPONSE);
    ln_wbuf_u32(&ep->tx, req->call_id);
    rc = ln_sig_encode(p->resp_sig, response, &ep->tx, p->max_size);
    if (rc == LN_OK)
        rc = ln_svc_frame_end(&ep->tx, start);
    if (rc != LN_OK) {
        ln_wbuf_reset(&ep->tx);
        return ln_set_error(p->clnt, rc, "service \"%s\": cannot encode the response: %s", p->name,
                            ln_last_error());
    }
    req->answered = 1;
    if (atomic_load_explicit(&p->tapped, memory_order_relaxed)) {
        size_t at = start + LN_SVC_HEADER_SIZE + 4; /* the payload after the call id */
        ln_svc_tap_call(p, req, 0, ep->tx.data + at, ep->tx.len - at);
    }
    if (send_tx(ep) != LN_OK)
        return ln_set_error(p->clnt, LN_ECONNECTION,
                            "service \"%s\": the caller is gone, response not delivered", p->name);
    return LN_OK;
}

int ln_service_request_respond_error(ln_service_request* req, const char* text)
{
    int rc = request_check(req);
    if (rc != LN_OK)
        return rc;
    if (req->answered)
        return ln_set_error(req->prov->clnt, LN_EINVAL, "service \"%s\": call already answered",
                            req->prov->name);
    rc = answer_error(req, LN_ESERVICE, text ? text : "");
    return rc == LN_OK ? LN_OK
                       : ln_set_error(req->prov->clnt, rc,
                                      "service \"%s\": the caller is gone, error not delivered",
                                      req->prov->name);
}

const char* ln_service_request_service_name(const ln_service_request* req)
{
    return request_check(req) == LN_OK ? req->prov->name : NULL;
}

/* ---- waitsets (waitset_internal.h) ---- */

int ln_provider_group_of(const ln_service_provider* p, ln_client** clnt, const char** group)
{
    int rc = provider_check(p);
    if (rc != LN_OK)
        return rc;
    if (p->group == NULL)
        return ln_set_error(p->clnt, LN_EINVAL,
                            "service '%s' is not registered: register it before attaching it",
                            p->name);
    *clnt = p->clnt;
    *group = p->group_name;
    return LN_OK;
}
