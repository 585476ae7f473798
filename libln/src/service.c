/* service.c — the caller side of services: looking a service up in the manager, connecting to
 * its provider (Unix socket on the same host, TCP otherwise, protected as svc_secure.h says),
 * and calls over that connection. */
#include <errno.h>
#include <math.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#include <sodium.h>

#include "net.h"
#include "svc_internal.h"
#include "svc_secure.h"

#define LN_SERVICE_MAGIC 0x4c4e5343u
#define RX_INITIAL 4096

struct ln_service {
    uint32_t magic;
    ln_client* clnt;
    char name[LN_SVC_MAX_NAME + 1];
    char md_name[LN_SVC_MAX_NAME + 1];
    uint64_t layout_hash;
    ln_sig* req_sig;
    ln_sig* resp_sig;
    size_t max_size;

    pthread_mutex_t lock; /* one call at a time; guards everything below */
    int fd;               /* -1: not connected */
    int is_unix;          /* fd is a Unix socket: a send to a closed one fails at once */
    int send_errno;       /* of the last send_tx, 0 if it went out */
    ln_svc_channel ch;    /* TCP with security: the keys; level NONE: plain */
    char provider[LN_PROTO_MAX_STR + 1];
    char via[LN_PROTO_MAX_STR + 16]; /* "unix:PATH" or "tcp:HOST:PORT", for texts */
    uint32_t last_call;
    ln_wbuf tx;
    uint8_t* rx;
    size_t rx_len, rx_cap;
    ln_arena arena; /* dynamic fields of the last response */
};

static int service_check(const ln_service* s)
{
    if (s == NULL || s->magic != LN_SERVICE_MAGIC)
        return ln_set_error(NULL, LN_EBADHANDLE, "invalid service handle");
    return LN_OK;
}

static void disconnect(ln_service* s)
{
    if (s->fd >= 0)
        close(s->fd);
    s->fd = -1;
    ln_svc_channel_wipe(&s->ch);
}

static void service_free(ln_service* s)
{
    disconnect(s);
    ln_sig_free(s->req_sig);
    ln_sig_free(s->resp_sig);
    ln_wbuf_free(&s->tx);
    free(s->rx);
    ln_arena_free(&s->arena);
    pthread_mutex_destroy(&s->lock);
    s->magic = 0;
    free(s);
}

static void service_close_fn(void* s) { ln_service_release(s); }

/* A caller registers nothing: after a reconnect it simply looks the service up again on its
 * next call that needs to. */
static int service_reclaim(ln_client* clnt, void* s)
{
    (void)clnt;
    (void)s;
    return LN_OK;
}

static const ln_client_port_ops service_ops = {service_close_fn, service_reclaim};

int ln_get_service(ln_client* clnt, ln_service** out, const char* name, const char* md_name,
                   uint64_t layout_hash, const char* signature)
{
    int rc = ln_client_check(clnt);
    if (rc != LN_OK)
        return rc;
    if (out == NULL)
        return ln_set_error(clnt, LN_EINVAL, "ln_get_service: out must not be NULL");
    *out = NULL;
    rc = ln_svc_check_names(clnt, "ln_get_service", name, md_name, signature);
    if (rc != LN_OK)
        return rc;
    ln_service* s = calloc(1, sizeof *s);
    if (s == NULL)
        return ln_set_error(clnt, LN_ENOMEM, "out of memory for service \"%s\"", name);
    s->clnt = clnt;
    s->fd = -1;
    snprintf(s->name, sizeof s->name, "%s", name);
    snprintf(s->md_name, sizeof s->md_name, "%s", md_name);
    s->layout_hash = layout_hash;
    s->max_size = LN_SERVICE_DEFAULT_MAX_SIZE;
    pthread_mutex_init(&s->lock, NULL);
    ln_wbuf_init(&s->tx);
    ln_arena_init(&s->arena, 0);
    rc = ln_svc_parse_signature(clnt, md_name, signature, &s->req_sig, &s->resp_sig);
    if (rc == LN_OK) {
        s->magic = LN_SERVICE_MAGIC;
        rc = ln_client_add_port(clnt, s, &service_ops, 0);
    }
    if (rc != LN_OK) {
        service_free(s);
        return rc;
    }
    *out = s;
    return LN_OK;
}

int ln_service_set_max_size(ln_service* s, size_t max_bytes)
{
    int rc = service_check(s);
    if (rc != LN_OK)
        return rc;
    if (max_bytes == 0 || max_bytes > ((size_t)1 << 31))
        return ln_set_error(s->clnt, LN_EINVAL, "service \"%s\": max size %zu is not in 1..2^31",
                            s->name, max_bytes);
    pthread_mutex_lock(&s->lock);
    s->max_size = max_bytes;
    pthread_mutex_unlock(&s->lock);
    return LN_OK;
}

int ln_service_release(ln_service* s)
{
    int rc = service_check(s);
    if (rc != LN_OK)
        return rc;
    ln_client_remove_port(s->clnt, s);
    service_free(s);
    return LN_OK;
}

/* ---- frames on the caller's connection ---- */

/* Receives until s->rx holds `need` bytes: waits for data, then takes whatever is there, so a
 * small frame costs one poll and one recv.  0, LN_NET_EOF or an errno value. */
static int fill(ln_service* s, size_t need, const struct timespec* deadline)
{
    while (s->rx_len < need) {
        int err = ln_net_wait_readable(s->fd, deadline, -1);
        if (err != 0)
            return err;
        ssize_t n = recv(s->fd, s->rx + s->rx_len, s->rx_cap - s->rx_len, 0);
        if (n > 0)
            s->rx_len += (size_t)n;
        else if (n == 0)
            return LN_NET_EOF;
        else if (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR)
            return errno;
    }
    return 0;
}

/* The frame in s->rx on a protected connection: only SEALED frames that open count.  A plain
 * ERROR is the provider refusing this connection before it could prove anything (the keys
 * differ, or a frame was altered on the way): reported as LN_EPERM, its text marked. */
static int open_frame(ln_service* s, uint16_t* type, ln_rbuf* body)
{
    size_t len = s->rx_len - LN_SVC_HEADER_SIZE;
    if (*type == LN_SVC_ERROR) {
        char text[LN_PROTO_MAX_STR + 1];
        ln_rbuf_init(body, s->rx + LN_SVC_HEADER_SIZE, len);
        ln_rbuf_u32(body);
        ln_rbuf_i32(body);
        ln_rbuf_str(body, text, sizeof text);
        return ln_set_error(s->clnt, LN_EPERM,
                            "service \"%s\": provider \"%s\" (%s) refused the protected "
                            "connection (unauthenticated answer): %s",
                            s->name, s->provider, s->via,
                            ln_rbuf_end(body) == LN_OK ? text : "(malformed)");
    }
    uint8_t* inner;
    size_t inner_len;
    int rc = *type == LN_SVC_SEALED
                 ? ln_svc_open(&s->ch, s->rx, s->rx_len, type, &inner, &inner_len)
                 : LN_EPERM;
    if (rc == LN_EPERM)
        return ln_set_error(s->clnt, LN_EPERM,
                            "service \"%s\": a frame from provider \"%s\" (%s) failed "
                            "authentication (forged, replayed, reordered or cut on the way); "
                            "connection closed",
                            s->name, s->provider, s->via);
    if (rc != LN_OK)
        return ln_set_error(s->clnt, LN_EPROTOCOL,
                            "service \"%s\": malformed frame inside a sealed frame from "
                            "provider \"%s\" (%s)",
                            s->name, s->provider, s->via);
    ln_rbuf_init(body, inner, inner_len);
    return LN_OK;
}

/* Reads one whole frame into s->rx.  LN_OK with type and body, or an error (recorded; the
 * caller disconnects).  The provider answers one frame per request, so any byte beyond the
 * frame is a protocol error. */
static int read_frame(ln_service* s, const struct timespec* deadline, uint16_t* type, ln_rbuf* body)
{
    if (s->rx_cap < RX_INITIAL) {
        uint8_t* rx = realloc(s->rx, RX_INITIAL);
        if (rx == NULL)
            return ln_set_error(s->clnt, LN_ENOMEM, "service \"%s\": out of memory", s->name);
        s->rx = rx;
        s->rx_cap = RX_INITIAL;
    }
    s->rx_len = 0;
    int err = fill(s, LN_SVC_HEADER_SIZE, deadline);
    uint32_t len = 0;
    if (err == 0) {
        int rc = ln_svc_parse_header(s->rx, s->max_size, &len, type);
        if (rc == LN_ETOOBIG)
            return ln_set_error(s->clnt, LN_ETOOBIG,
                                "service \"%s\": response of %u bytes exceeds this caller's "
                                "maximum of %zu (ln_service_set_max_size)",
                                s->name, (unsigned)len, s->max_size);
        if (rc != LN_OK)
            return ln_set_error(s->clnt, LN_EPROTOCOL,
                                "service \"%s\": malformed frame from provider \"%s\" (%s)",
                                s->name, s->provider, s->via);
        size_t total = LN_SVC_HEADER_SIZE + (size_t)len;
        if (total > s->rx_cap) {
            uint8_t* rx = realloc(s->rx, total);
            if (rx == NULL)
                return ln_set_error(s->clnt, LN_ENOMEM,
                                    "service \"%s\": out of memory for a "
                                    "response of %u bytes",
                                    s->name, (unsigned)len);
            s->rx = rx;
            s->rx_cap = total;
        }
        err = fill(s, total, deadline);
        if (err == 0 && s->rx_len != total)
            return ln_set_error(s->clnt, LN_EPROTOCOL,
                                "service \"%s\": provider \"%s\" (%s) sent more than one frame",
                                s->name, s->provider, s->via);
    }
    if (err == ETIMEDOUT)
        return ln_set_error(s->clnt, LN_ETIMEOUT,
                            "service \"%s\": no response from provider \"%s\" (%s) in time",
                            s->name, s->provider, s->via);
    if (err == LN_NET_EOF)
        return ln_set_error(s->clnt, LN_ECONNECTION,
                            "service \"%s\": provider \"%s\" (%s) closed the connection", s->name,
                            s->provider, s->via);
    if (err != 0)
        return ln_set_errno_error(s->clnt, err,
                                  "service \"%s\": connection to provider \"%s\" (%s) failed",
                                  s->name, s->provider, s->via);
    if (s->ch.level != LN_SVC_SEC_NONE)
        return open_frame(s, type, body);
    ln_rbuf_init(body, s->rx + LN_SVC_HEADER_SIZE, len);
    return LN_OK;
}

/* An ERROR frame into its code and text (recorded). */
static int take_error(ln_service* s, ln_rbuf* body)
{
    char text[LN_PROTO_MAX_STR + 1];
    ln_rbuf_u32(body); /* call id: 0 or this call's */
    int code = ln_rbuf_i32(body);
    ln_rbuf_str(body, text, sizeof text);
    if (ln_rbuf_end(body) != LN_OK || code >= 0 || code < -LN_ERROR_COUNT)
        return ln_set_error(s->clnt, LN_EPROTOCOL,
                            "service \"%s\": malformed ERROR frame from provider \"%s\"", s->name,
                            s->provider);
    return ln_set_error(s->clnt, code, "service \"%s\" (provider \"%s\"): %s", s->name, s->provider,
                        text);
}

/* Sends the one frame in b (sealed first on a protected connection: b changes). */
static int send_buf(ln_service* s, ln_wbuf* b, const struct timespec* deadline)
{
    if (s->ch.level != LN_SVC_SEC_NONE) {
        int rc = ln_svc_seal(&s->ch, b, 0);
        if (rc != LN_OK)
            return ln_set_error(s->clnt, rc, "service \"%s\": cannot seal a frame: %s", s->name,
                                ln_strerror(rc));
    }
    int err = ln_net_write_all(s->fd, b->data, b->len, deadline, -1);
    s->send_errno = err;
    if (err == ETIMEDOUT)
        return ln_set_error(s->clnt, LN_ETIMEOUT,
                            "service \"%s\": provider \"%s\" (%s) does not take the request",
                            s->name, s->provider, s->via);
    if (err != 0)
        return ln_set_errno_error(s->clnt, err,
                                  "service \"%s\": cannot send to provider \"%s\" (%s)", s->name,
                                  s->provider, s->via);
    return LN_OK;
}

/* ---- connecting ---- */

static int open_connection(ln_service* s, const char* host_id, const char* unix_path,
                           const char* tcp_host, uint16_t tcp_port, const struct timespec* deadline)
{
    char mine[LN_HOST_ID_MAX];
    ln_host_id(mine, sizeof mine);
    int err = ENOENT;
    if (unix_path[0] != '\0' && strcmp(host_id, mine) == 0) {
        err = ln_svc_connect_unix(unix_path, deadline, &s->fd);
        if (err == 0) {
            s->is_unix = 1;
            snprintf(s->via, sizeof s->via, "unix:%s", unix_path);
            return LN_OK;
        }
    }
    s->is_unix = 0;
    if (tcp_port != 0 && tcp_host[0] != '\0') {
        char port[8];
        snprintf(port, sizeof port, "%u", tcp_port);
        snprintf(s->via, sizeof s->via, "tcp:%s:%u", tcp_host, tcp_port);
        struct addrinfo* ai;
        int gai = ln_net_resolve(tcp_host, port, &ai);
        if (gai != 0)
            return ln_set_error(s->clnt, LN_ECONNECTION,
                                "service \"%s\": cannot resolve provider host \"%s\": %s", s->name,
                                tcp_host, gai_strerror(gai));
        err = ln_net_connect(ai, deadline, -1, &s->fd);
        freeaddrinfo(ai);
        if (err == 0)
            return LN_OK;
    } else {
        snprintf(s->via, sizeof s->via, "unix:%s", unix_path);
    }
    if (err == ETIMEDOUT)
        return ln_set_error(s->clnt, LN_ETIMEOUT,
                            "service \"%s\": connecting to provider \"%s\" (%s) timed out", s->name,
                            s->provider, s->via);
    return ln_set_errno_error(s->clnt, err == 0 ? ECONNREFUSED : err,
                              "service \"%s\": cannot connect to provider \"%s\" (%s)", s->name,
                              s->provider, s->via);
}

/* The handshake of secure_connection() under `k` (a protected level). */
static int secure_with(ln_service* s, const ln_svc_key* k, const struct timespec* deadline)
{
    int rc;
    if (sodium_init() < 0)
        return ln_set_error(s->clnt, LN_ESYS, "service \"%s\": libsodium is unusable", s->name);
    uint8_t mine[LN_SVC_NONCE_BYTES];
    ln_svc_nonce(mine);
    unsigned offer = ln_svc_aead_offer();
    ln_wbuf b;
    ln_wbuf_init(&b);
    size_t start = ln_proto_frame_begin(&b, LN_SVC_SECURE);
    ln_wbuf_u32(&b, LN_SVC_MAGIC);
    ln_wbuf_u16(&b, LN_SVC_VERSION);
    ln_wbuf_u16(&b, (uint16_t)k->level);
    ln_wbuf_u16(&b, (uint16_t)offer);
    ln_wbuf_str(&b, s->name);
    ln_wbuf_bytes(&b, mine, sizeof mine);
    rc = ln_svc_frame_end(&b, start);
    if (rc == LN_OK)
        rc = send_buf(s, &b, deadline);
    ln_wbuf_free(&b);
    uint16_t type;
    ln_rbuf answer;
    if (rc == LN_OK)
        rc = read_frame(s, deadline, &type, &answer);
    if (rc != LN_OK)
        return rc;
    if (type == LN_SVC_ERROR)
        return take_error(s, &answer);
    uint16_t level = ln_rbuf_u16(&answer);
    int aead = ln_rbuf_u16(&answer);
    uint8_t theirs[LN_SVC_NONCE_BYTES];
    ln_svc_read_nonce(&answer, theirs);
    if (type != LN_SVC_SECURED || ln_rbuf_end(&answer) != LN_OK)
        return ln_set_error(s->clnt, LN_EPROTOCOL,
                            "service \"%s\": provider \"%s\" (%s) did not answer SECURE", s->name,
                            s->provider, s->via);
    if (level != k->level || ln_svc_aead_pick(offer, (unsigned)aead) != aead)
        return ln_set_error(s->clnt, LN_EPERM,
                            "service \"%s\": provider \"%s\" (%s) answered with security "
                            "%s and AEAD %d, this caller uses %s (AEADs 0x%x)",
                            s->name, s->provider, s->via, ln_svc_level_name(level), aead,
                            ln_svc_level_name(k->level), offer);
    rc = ln_svc_channel_init(&s->ch, k, aead, mine, theirs, s->name, 1);
    if (rc != LN_OK)
        return ln_set_error(s->clnt, rc, "service \"%s\": cannot derive the channel keys", s->name);
    return LN_OK;
}

/* On a new TCP connection: SECURE with our nonce, SECURED with the provider's, then the keys
 * (svc_secure.h).  Level none sends nothing: the provider refuses HELLO unless it has none
 * too.  LN_OK or an error (recorded). */
static int secure_connection(ln_service* s, const struct timespec* deadline)
{
    ln_svc_key key;
    int rc = ln_svc_key_get(s->clnt, &key);
    if (rc != LN_OK)
        return ln_set_error(s->clnt, rc, "service \"%s\": %s", s->name, ln_last_error());
    if (key.level != LN_SVC_SEC_NONE)
        rc = secure_with(s, &key, deadline);
    sodium_memzero(key.key, sizeof key.key); /* on every way out */
    return rc;
}

/* Looks the service up, connects and greets the provider. */
static int connect_service(ln_service* s, const struct timespec* deadline)
{
    ln_wbuf body;
    ln_wbuf_init(&body);
    ln_msg_find_service find = {.name = ln_strv_of(s->name),
                                .md_name = ln_strv_of(s->md_name),
                                .layout_hash = s->layout_hash};
    ln_msg_find_service_write_after_id(&body, &find);
    uint16_t reply_type;
    ln_rbuf reply;
    int rc = ln_client_request(s->clnt, LN_MSG_FIND_SERVICE, &body, &reply_type, &reply);
    ln_wbuf_free(&body);
    if (rc != LN_OK)
        return ln_set_error(s->clnt, rc, "cannot call service \"%s\": %s", s->name,
                            ln_last_error());
    char host_id[LN_PROTO_MAX_STR + 1], unix_path[LN_PROTO_MAX_STR + 1];
    char tcp_host[LN_PROTO_MAX_STR + 1], signature[LN_PROTO_MAX_STR + 1];
    ln_msg_service_info info;
    if (ln_msg_service_info_read_after_id(&reply, &info) != LN_OK ||
        ln_strv_copy(info.provider, s->provider, sizeof s->provider) != LN_OK ||
        ln_strv_copy(info.host_id, host_id, sizeof host_id) != LN_OK ||
        ln_strv_copy(info.unix_path, unix_path, sizeof unix_path) != LN_OK ||
        ln_strv_copy(info.tcp_host, tcp_host, sizeof tcp_host) != LN_OK ||
        ln_strv_copy(info.signature, signature, sizeof signature) != LN_OK)
        return ln_set_error(s->clnt, LN_EPROTOCOL,
                            "cannot call service \"%s\": malformed "
                            "SERVICE_INFO",
                            s->name);
    uint16_t tcp_port = info.tcp_port;
    rc = open_connection(s, host_id, unix_path, tcp_host, tcp_port, deadline);
    if (rc == LN_OK && !s->is_unix)
        rc = secure_connection(s, deadline);
    if (rc != LN_OK) {
        disconnect(s);
        return rc;
    }

    ln_wbuf hello;
    ln_wbuf_init(&hello);
    size_t start = ln_proto_frame_begin(&hello, LN_SVC_HELLO);
    ln_wbuf_u32(&hello, LN_SVC_MAGIC);
    ln_wbuf_u16(&hello, LN_SVC_VERSION);
    ln_wbuf_str(&hello, s->name);
    ln_wbuf_u64(&hello, s->layout_hash);
    ln_wbuf_str(&hello, ln_client_name(s->clnt)); /* the caller, for recorded calls */
    rc = ln_svc_frame_end(&hello, start);
    if (rc == LN_OK)
        rc = send_buf(s, &hello, deadline);
    ln_wbuf_free(&hello);
    uint16_t type;
    ln_rbuf answer;
    if (rc == LN_OK)
        rc = read_frame(s, deadline, &type, &answer);
    if (rc == LN_OK && type == LN_SVC_ERROR)
        rc = take_error(s, &answer);
    else if (rc == LN_OK && (type != LN_SVC_WELCOME || ln_rbuf_end(&answer) != LN_OK))
        rc = ln_set_error(s->clnt, LN_EPROTOCOL,
                          "service \"%s\": provider \"%s\" (%s) did not answer HELLO", s->name,
                          s->provider, s->via);
    if (rc != LN_OK)
        disconnect(s);
    return rc;
}

/* 1 if the idle connection was closed by the provider (or has unexpected data): it must not
 * carry a request, which would then be lost without knowing whether it ran.  Unix sockets
 * skip this check (a system call per call): a send to a closed one fails with EPIPE before
 * anything was delivered, and the call is retried on a new connection. */
static int connection_stale(const ln_service* s)
{
    struct pollfd pfd = {.fd = s->fd, .events = POLLIN};
    return poll(&pfd, 1, 0) != 0;
}

/* ---- calls ---- */

/* The first half of a call: connects if needed and sends the request (s->last_call). */
static int send_request(ln_service* s, const void* request, const struct timespec* deadline)
{
    int rc;
    if (s->fd >= 0 && !s->is_unix && connection_stale(s))
        disconnect(s);
    int reused = s->fd >= 0;
    if (s->fd < 0 && (rc = connect_service(s, deadline)) != LN_OK)
        return rc;
    uint32_t call_id = ++s->last_call;
    if (call_id == 0)
        call_id = ++s->last_call;
    ln_wbuf_reset(&s->tx);
    size_t start = ln_proto_frame_begin(&s->tx, LN_SVC_REQUEST);
    ln_wbuf_u32(&s->tx, call_id);
    rc = ln_sig_encode(s->req_sig, request, &s->tx, s->max_size);
    if (rc != LN_OK)
        return ln_set_error(s->clnt, rc, "service \"%s\": cannot encode the request: %s", s->name,
                            ln_last_error());
    rc = ln_svc_frame_end(&s->tx, start);
    if (rc != LN_OK)
        return ln_set_error(s->clnt, rc, "service \"%s\": cannot encode the request", s->name);
    rc = send_buf(s, &s->tx, deadline);
    if (rc != LN_OK && reused && s->is_unix &&
        (s->send_errno == EPIPE || s->send_errno == ECONNRESET || s->send_errno == ENOTCONN)) {
        /* The provider had closed this connection before the request went out (it was
         * restarted): nothing was delivered, so sending again on a new connection is safe. */
        disconnect(s);
        if ((rc = connect_service(s, deadline)) != LN_OK)
            return rc;
        rc = send_buf(s, &s->tx, deadline);
    }
    if (rc != LN_OK)
        disconnect(s);
    return rc;
}

/* The second half of a call: waits for the answer to the request send_request sent. */
static int receive_response(ln_service* s, void* response, const struct timespec* deadline)
{
    uint32_t call_id = s->last_call;
    if (s->fd < 0)
        return ln_set_error(s->clnt, LN_ECONNECTION,
                            "service \"%s\": no request is waiting "
                            "for an answer",
                            s->name);
    uint16_t type;
    ln_rbuf body;
    int rc = read_frame(s, deadline, &type, &body);
    if (rc != LN_OK) {
        disconnect(s);
        return rc;
    }
    if (type == LN_SVC_ERROR) {
        /* An error about the connection (call id 0) ends it; one about this call does not. */
        ln_rbuf peek = body;
        if (ln_rbuf_u32(&peek) == 0)
            disconnect(s);
        return take_error(s, &body);
    }
    if (type != LN_SVC_RESPONSE || ln_rbuf_u32(&body) != call_id) {
        disconnect(s);
        return ln_set_error(s->clnt, LN_EPROTOCOL,
                            "service \"%s\": provider \"%s\" sent an unexpected frame", s->name,
                            s->provider);
    }
    ln_arena_reset(&s->arena);
    rc = ln_sig_decode(s->resp_sig, body.p, body.left, response, &s->arena, s->max_size);
    if (rc != LN_OK)
        return ln_set_error(s->clnt, rc, "service \"%s\": bad response from provider \"%s\": %s",
                            s->name, s->provider, ln_last_error());
    return LN_OK;
}

static int call_locked(ln_service* s, const void* request, void* response,
                       const struct timespec* deadline)
{
    int rc = send_request(s, request, deadline);
    return rc != LN_OK ? rc : receive_response(s, response, deadline);
}

int ln_svc_call_send(ln_service* s, const void* request, const struct timespec* deadline)
{
    return send_request(s, request, deadline);
}

int ln_svc_call_receive(ln_service* s, void* response, const struct timespec* deadline)
{
    return receive_response(s, response, deadline);
}

int ln_service_call(ln_service* s, const void* request, void* response, double timeout)
{
    int rc = service_check(s);
    if (rc != LN_OK)
        return rc;
    if (isnan(timeout))
        return ln_set_error(s->clnt, LN_EINVAL, "service \"%s\": timeout is NaN", s->name);
    if ((request == NULL && ln_sig_size(s->req_sig) > 0) ||
        (response == NULL && ln_sig_size(s->resp_sig) > 0))
        return ln_set_error(s->clnt, LN_EINVAL, "service \"%s\": request or response is NULL",
                            s->name);
    struct timespec ts;
    const struct timespec* deadline = isinf(timeout) ? NULL : ln_net_deadline(&ts, timeout);
    pthread_mutex_lock(&s->lock);
    rc = call_locked(s, request, response, deadline);
    pthread_mutex_unlock(&s->lock);
    return rc;
}
