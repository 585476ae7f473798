/* client_conn.c — the client's TCP connection to its manager: the HELLO/WELCOME handshake,
 * serialized request/answer round trips (docs/protocol.md) and the monitor thread that
 * reconnects after the manager went away and re-registers the client's ports and providers.
 * Failures are recorded with the manager's address and the request; a connection that can no
 * longer be trusted to be in step with the manager is dropped (and, with a monitor, replaced). */
#include <assert.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <unistd.h>

#include "client_auth.h"
#include "client_conn.h"
#include "net.h"

#define MAX_ADDRESS LN_CLIENT_MAX_ADDRESS

/* Drops connection k (the client's own under the request lock, or the one the monitor is
 * setting up).  With a monitor the client's socket is only shut down: the monitor, which
 * polls it, sees the hang-up, closes it and reconnects. */
static void disconnect(ln_client* c, struct ln_conn* k)
{
    if (k->fd >= 0 && c->monitored && k == &c->conn) {
        shutdown(k->fd, SHUT_RDWR);
    } else if (k->fd >= 0) {
        close(k->fd);
        k->fd = -1;
    }
    k->usable = 0;
    k->broken = 1;
    k->stale_answers = 0;
}

/* Records a failed transfer (errno value, ETIMEDOUT or LN_NET_EOF) with context `what`. */
static int io_error(ln_client* c, int err, const char* what)
{
    if (err == LN_NET_EOF)
        return ln_set_error(c, LN_ECONNECTION, "%s: manager closed the connection", what);
    if (err == ETIMEDOUT && c->timeout >= 0)
        return ln_set_error(c, LN_ETIMEOUT, "%s: timed out after %g s", what, c->timeout);
    if (err == ECANCELED)
        return ln_set_error(c, LN_ECONNECTION, "%s: the client is being destroyed", what);
    return ln_set_errno_error(c, err, "%s", what);
}

static int malformed(ln_client* c, struct ln_conn* k, const char* request, const char* why)
{
    disconnect(c, k);
    return ln_set_error(c, LN_EPROTOCOL,
                        "malformed answer from manager %s to %s (%s); connection closed",
                        c->address, request, why);
}

static int unexpected(ln_client* c, struct ln_conn* k, const char* request, uint16_t type)
{
    char why[64];
    snprintf(why, sizeof why, "unexpected %s frame", ln_proto_type_name(type));
    return malformed(c, k, request, why);
}

/* Sends the frames in k->tx; any failure leaves half a frame behind, so it disconnects. */
static int send_tx(ln_client* c, struct ln_conn* k, const char* request,
                   const struct timespec* deadline)
{
    int err = ln_net_write_all(k->fd, k->tx.data, k->tx.len, deadline, c->cancel_fd);
    if (err == 0)
        return LN_OK;
    char what[MAX_ADDRESS + 64];
    snprintf(what, sizeof what, "cannot send %s to manager %s", request, c->address);
    disconnect(c, k);
    return io_error(c, err, what);
}

/* Reads one frame into k->rx.  A timeout before its first byte keeps the connection (the
 * answer may still come and is then skipped); every other failure closes it. */
static int read_frame(ln_client* c, struct ln_conn* k, const char* request,
                      const struct timespec* deadline, uint16_t* type, ln_rbuf* body)
{
    char what[MAX_ADDRESS + 64];
    snprintf(what, sizeof what, "no answer from manager %s to %s", c->address, request);
    int err = ln_net_wait_readable(k->fd, deadline, c->cancel_fd);
    if (err == ETIMEDOUT)
        return io_error(c, err, what);
    uint8_t header[LN_PROTO_HEADER_SIZE];
    uint32_t len = 0;
    if (err == 0)
        err = ln_net_read_all(k->fd, header, sizeof header, deadline, c->cancel_fd);
    if (err == 0 && ln_proto_parse_header(header, &len, type) != LN_OK) {
        ln_rbuf r;
        ln_rbuf_init(&r, header, sizeof header);
        char why[64];
        uint32_t length = ln_rbuf_u32(&r);
        snprintf(why, sizeof why, "frame length %u, type %u", (unsigned)length,
                 (unsigned)ln_rbuf_u16(&r));
        return malformed(c, k, request, why);
    }
    if (err == 0 && len > k->rx_cap) {
        uint8_t* rx = realloc(k->rx, len);
        if (rx == NULL) {
            err = ENOMEM;
        } else {
            k->rx = rx;
            k->rx_cap = len;
        }
    }
    if (err == 0)
        err = ln_net_read_all(k->fd, k->rx, len, deadline, c->cancel_fd);
    if (err != 0) {
        disconnect(c, k);
        return io_error(c, err, what);
    }
    ln_rbuf_init(body, k->rx, len);
    if (!ln_proto_to_client(*type))
        return unexpected(c, k, request, *type);
    /* A WELCOME of another protocol version may have other fields: handshake() says so. */
    ln_rbuf peek = *body;
    if ((*type != LN_MSG_WELCOME || ln_rbuf_u16(&peek) == LN_PROTO_VERSION) &&
        ln_proto_check_fields(*type, body) != LN_OK)
        return malformed(c, k, request, "fields do not match the frame type");
    return LN_OK;
}

/* The rest of a checked ERROR body (after its request id): records the manager's text behind
 * `prefix` and returns its code. */
static int take_error(ln_client* c, const char* request, ln_rbuf* r, const char* prefix)
{
    ln_msg_error e = {0};
    ln_msg_error_read_after_id(r, &e); /* read_frame checked it */
    int32_t code = e.code;
    int len = (int)e.text.len;
    if (code >= 0 || code < -LN_ERROR_COUNT) /* well-formed, so the connection stays */
        return ln_set_error(c, LN_EPROTOCOL, "manager %s answered %s with unknown code %d: %.*s",
                            c->address, request, (int)code, len, e.text.s);
    return ln_set_error(c, code, "%s%.*s", prefix, len, e.text.s);
}

/* ---- handshake ------------------------------------------------------------------------- */

/* The manager did not admit the client by its credentials and sent CHALLENGE (in *r): prove
 * the client key with AUTH, take AUTH_OK and check the manager's proof, so that *type and *r
 * hold the frame after it (WELCOME, or the ERROR of a refusal).  Without a key file AUTH
 * carries no proof: the manager's refusal says why. */
static int answer_challenge(ln_client* c, struct ln_conn* k, const char* name,
                            const struct timespec* deadline, uint16_t* type, ln_rbuf* r)
{
    ln_msg_challenge ch = {0};
    ln_msg_challenge_read(r, &ch); /* read_frame checked it */
    char instance[LN_PROTO_MAX_STR + 1];
    ln_strv_copy(ch.instance_name, instance, sizeof instance);
    uint8_t key[LN_AUTH_BYTES], mine[LN_AUTH_BYTES], theirs[LN_AUTH_BYTES];
    uint8_t proof[LN_AUTH_BYTES];
    if (ln_auth_from_hex(ch.nonce.s, ch.nonce.len, theirs) != 0)
        return malformed(c, k, "HELLO", "CHALLENGE nonce is not 64 hex digits");
    char path[4096], why[LN_ERROR_TEXT_MAX];
    int keyed = ln_auth_load_key(key, path, sizeof path, why, sizeof why);
    if (keyed == LN_EPERM) {
        disconnect(c, k);
        return ln_set_error(c, LN_EPERM,
                            "manager %s admits client \"%s\" of instance \"%s\" "
                            "only with the client key: %s",
                            c->address, name, instance, why);
    }
    char nonce_hex[LN_AUTH_HEX + 1], proof_hex[LN_AUTH_HEX + 1] = "";
    ln_auth_random(mine, sizeof mine);
    ln_auth_to_hex(mine, nonce_hex);
    if (keyed == LN_OK) {
        ln_auth_mac(key, LN_AUTH_CLIENT, instance, name, theirs, mine, proof);
        ln_auth_to_hex(proof, proof_hex);
    }
    ln_wbuf_reset(&k->tx);
    ln_msg_auth auth = {.nonce = ln_strv_of(nonce_hex), .proof = ln_strv_of(proof_hex)};
    int rc = ln_msg_auth_frame(&k->tx, &auth);
    if (rc == LN_OK)
        rc = send_tx(c, k, "AUTH", deadline);
    if (rc == LN_OK)
        rc = read_frame(c, k, "AUTH", deadline, type, r);
    /* With a proof sent, only AUTH_OK (the manager's proof) or ERROR (its refusal) may follow:
     * a manager that answers anything else has not shown that it holds the key.  Without a
     * key there is nothing to check an AUTH_OK against. */
    if (rc == LN_OK && *type != LN_MSG_ERROR && (*type == LN_MSG_AUTH_OK) != (keyed == LN_OK)) {
        if (keyed != LN_OK) {
            rc = malformed(c, k, "AUTH", "AUTH_OK to a client that sent no proof");
        } else {
            disconnect(c, k);
            rc = ln_set_error(c, LN_EPERM,
                              "manager %s did not prove the client key of instance \"%s\" "
                              "(it answered AUTH with message %u); connection closed",
                              c->address, instance, (unsigned)*type);
        }
    }
    if (rc == LN_OK && *type == LN_MSG_AUTH_OK) {
        ln_msg_auth_ok ok = {0};
        ln_msg_auth_ok_read(r, &ok);
        uint8_t expected[LN_AUTH_BYTES];
        ln_auth_mac(key, LN_AUTH_MANAGER, instance, name, theirs, mine, expected);
        if (ln_auth_from_hex(ok.proof.s, ok.proof.len, proof) != 0 ||
            ln_auth_differ(proof, expected)) {
            disconnect(c, k);
            rc = ln_set_error(c, LN_EPERM,
                              "manager %s failed to prove the client key of "
                              "instance \"%s\": it is not that instance's manager or its key "
                              "differs from '%s'; connection closed",
                              c->address, instance, path);
        }
        if (rc == LN_OK) {
            ln_auth_mac(key, LN_AUTH_SESSION, instance, name, theirs, mine, k->session_key);
            k->has_session_key = 1;
            rc = read_frame(c, k, "AUTH", deadline, type, r);
        }
    }
    ln_auth_wipe(key, sizeof key);
    return rc;
}

/* HELLO as `name` with `flags`, then WELCOME.  A first handshake takes the manager's client
 * id, name and instance; a reconnect keeps the client's name (the manager's may differ if it
 * was taken meanwhile) and insists on the same instance. */
static int handshake(ln_client* c, struct ln_conn* k, const char* name, uint32_t flags,
                     const struct timespec* deadline)
{
    ln_wbuf_reset(&k->tx);
    char host_id[LN_HOST_ID_MAX];
    ln_host_id(host_id, sizeof host_id); /* the manager finds this host's ln_daemon by it */
    ln_msg_hello hello = {.magic = LN_PROTO_MAGIC,
                          .version = LN_PROTO_VERSION,
                          .pid = (uint32_t)c->pid,
                          .client_name = ln_strv_of(name),
                          .libln_version = ln_strv_of(ln_version()),
                          .host_id = ln_strv_of(host_id),
                          .flags = flags};
    int rc = ln_msg_hello_frame(&k->tx, &hello);
    if (rc != LN_OK)
        return ln_set_error(c, rc, "cannot encode HELLO: %s", ln_strerror(rc));
    rc = send_tx(c, k, "HELLO", deadline);
    uint16_t type = 0;
    ln_rbuf r;
    if (rc == LN_OK)
        rc = read_frame(c, k, "HELLO", deadline, &type, &r);
    if (rc == LN_OK && type == LN_MSG_CHALLENGE)
        rc = answer_challenge(c, k, name, deadline, &type, &r);
    if (rc != LN_OK)
        return rc;
    if (type == LN_MSG_ERROR) {
        char prefix[MAX_ADDRESS + LN_PROTO_MAX_STR + 64];
        snprintf(prefix, sizeof prefix, "manager %s refused client \"%s\": ", c->address, name);
        if (ln_rbuf_u32(&r) != 0)
            return malformed(c, k, "HELLO", "ERROR with a request id");
        return take_error(c, "HELLO", &r, prefix);
    }
    if (type != LN_MSG_WELCOME)
        return unexpected(c, k, "HELLO", type);
    ln_rbuf peek = r; /* a WELCOME of another version may have other fields */
    uint16_t version = ln_rbuf_u16(&peek);
    if (version != LN_PROTO_VERSION)
        return ln_set_error(c, LN_EVERSION,
                            "manager %s: client speaks protocol %d, manager speaks %u", c->address,
                            LN_PROTO_VERSION, (unsigned)version);
    ln_msg_welcome welcome = {0};
    ln_msg_welcome_read(&r, &welcome); /* read_frame checked it */
    uint32_t id = welcome.client_id;
    char given[LN_PROTO_MAX_STR + 1], instance[LN_PROTO_MAX_STR + 1];
    ln_strv_copy(welcome.client_name, given, sizeof given);
    ln_strv_copy(welcome.instance_name, instance, sizeof instance);
    if (given[0] == '\0')
        return malformed(c, k, "HELLO", "WELCOME with an empty client name");
    if (flags & LN_PROTO_HELLO_RECONNECT) {
        if (strcmp(instance, c->instance) != 0)
            return ln_set_error(c, LN_ECONNECTION,
                                "manager %s now serves instance \"%s\", not \"%s\"", c->address,
                                instance, c->instance);
    } else {
        memcpy(c->name, given, sizeof c->name);
        memcpy(c->instance, instance, sizeof c->instance);
    }
    c->client_id = id;
    return LN_OK;
}

/* ---- requests -------------------------------------------------------------------------- */

/* A PORT_OK for a request that timed out: the manager holds a port nobody knows of, so give
 * it back.  Its OK answer is skipped like any other stale answer. */
static int release_stale_port(ln_client* c, struct ln_conn* k, ln_rbuf* r,
                              const struct timespec* deadline)
{
    ln_msg_port_ok ok = {0};
    ln_msg_port_ok_read_after_id(r, &ok); /* read_frame checked it */
    if (++k->last_request_id == 0)
        k->last_request_id = 1;
    ln_wbuf_reset(&k->tx);
    ln_msg_close_port close = {.request_id = k->last_request_id, .port_id = ok.port_id};
    int rc = ln_msg_close_port_frame(&k->tx, &close);
    if (rc == LN_OK)
        rc = send_tx(c, k, "CLOSE_PORT", deadline);
    if (rc == LN_OK)
        k->stale_answers++;
    return rc;
}

static int round_trip(ln_client* c, struct ln_conn* k, uint16_t type, const ln_wbuf* body,
                      uint16_t* reply_type, ln_rbuf* reply)
{
    const char* request = ln_proto_type_name(type);
    if (!k->usable)
        return ln_set_error(c, LN_ECONNECTION,
                            c->monitored ? "cannot send %s: the connection to manager %s was "
                                           "lost; reconnecting"
                                         : "cannot send %s: the connection to manager %s was "
                                           "lost earlier",
                            request, c->address);
    if (++k->last_request_id == 0)
        k->last_request_id = 1;
    uint32_t id = k->last_request_id;
    ln_wbuf_reset(&k->tx);
    size_t start = ln_proto_frame_begin(&k->tx, type);
    ln_wbuf_u32(&k->tx, id);
    if (body != NULL)
        ln_wbuf_bytes(&k->tx, body->data, body->len);
    int rc = ln_proto_frame_end(&k->tx, start);
    if (rc != LN_OK)
        return ln_set_error(c, rc, "cannot encode %s: %s", request, ln_strerror(rc));

    struct timespec ts;
    const struct timespec* deadline = ln_net_deadline(&ts, c->timeout);
    rc = send_tx(c, k, request, deadline);
    uint16_t atype = 0;
    while (rc == LN_OK) {
        rc = read_frame(c, k, request, deadline, &atype, reply);
        if (rc == LN_ETIMEOUT && !k->broken)
            k->stale_answers++; /* the answer is still due: skip it when it comes */
        if (rc != LN_OK)
            return rc;
        uint32_t answer_id = ln_rbuf_u32(reply); /* every checked answer but WELCOME has one */
        if (atype == LN_MSG_WELCOME)
            return unexpected(c, k, request, atype);
        if (answer_id == id)
            break;
        if (answer_id == 0 || k->stale_answers == 0)
            return malformed(c, k, request, "answer to a request that was never sent");
        k->stale_answers--;
        if (atype == LN_MSG_PORT_OK)
            rc = release_stale_port(c, k, reply, deadline);
    }
    if (rc != LN_OK)
        return rc;
    if (atype == LN_MSG_ERROR)
        return take_error(c, request, reply, "");
    if (atype != ln_proto_answer_type(type))
        return unexpected(c, k, request, atype);
    *reply_type = atype;
    return LN_OK;
}

/* Each thread's copy of its last answer: the client's receive buffer is reused by the next
 * request of any thread as soon as the lock is released. */
static pthread_key_t reply_key;
static pthread_once_t reply_once = PTHREAD_ONCE_INIT;

struct reply_copy {
    uint8_t* data;
    size_t cap;
};

static void reply_free(void* p)
{
    struct reply_copy* r = p;
    free(r->data);
    free(r);
}

static void reply_key_init(void) { pthread_key_create(&reply_key, reply_free); }

/* Copies *reply into the calling thread's buffer and points *reply at it. */
static int copy_reply(ln_client* c, ln_rbuf* reply)
{
    pthread_once(&reply_once, reply_key_init);
    struct reply_copy* r = pthread_getspecific(reply_key);
    if (r == NULL) {
        r = calloc(1, sizeof *r);
        if (r == NULL || pthread_setspecific(reply_key, r) != 0) {
            free(r);
            return ln_set_error(c, LN_ENOMEM, "out of memory for a manager answer");
        }
    }
    if (reply->left > r->cap) {
        uint8_t* data = realloc(r->data, reply->left);
        if (data == NULL)
            return ln_set_error(c, LN_ENOMEM, "out of memory for a manager answer");
        r->data = data;
        r->cap = reply->left;
    }
    if (reply->left > 0)
        memcpy(r->data, reply->p, reply->left);
    reply->p = r->data;
    return LN_OK;
}

static _Thread_local uint64_t request_gen;

uint64_t ln_client_request_gen(void) { return request_gen; }

int ln_client_session_key(ln_client* clnt, uint8_t out[32])
{
    pthread_mutex_lock(&clnt->request_lock);
    int has = clnt->conn.has_session_key;
    if (has)
        memcpy(out, clnt->conn.session_key, sizeof clnt->conn.session_key);
    pthread_mutex_unlock(&clnt->request_lock);
    return has ? LN_OK : LN_ENOTFOUND;
}

static int check_body(ln_client* clnt, uint16_t type, const ln_wbuf* body)
{
    if (body != NULL && body->failed)
        return ln_set_error(clnt, body->failed, "cannot encode %s: %s", ln_proto_type_name(type),
                            body->failed == LN_EINVAL
                                ? "a text field is NULL, over 1024 bytes or not UTF-8"
                                : ln_strerror(body->failed));
    return LN_OK;
}

int ln_client_request_locked(ln_client* clnt, uint16_t type, const ln_wbuf* body,
                             uint16_t* reply_type, ln_rbuf* reply)
{
    struct ln_conn* k = clnt->reclaim_conn != NULL ? clnt->reclaim_conn : &clnt->conn;
    int rc = check_body(clnt, type, body);
    if (rc == LN_OK)
        rc = round_trip(clnt, k, type, body, reply_type, reply);
    if (rc == LN_OK)
        rc = copy_reply(clnt, reply);
    return rc;
}

int ln_client_request(ln_client* clnt, uint16_t type, const ln_wbuf* body, uint16_t* reply_type,
                      ln_rbuf* reply)
{
    assert(ln_proto_answer_type(type) != 0 && reply_type != NULL && reply != NULL);
    int rc = ln_client_check(clnt);
    if (rc != LN_OK)
        return rc;
    pthread_mutex_lock(&clnt->request_lock);
    rc = check_body(clnt, type, body);
    if (rc == LN_OK)
        rc = round_trip(clnt, &clnt->conn, type, body, reply_type, reply);
    if (rc == LN_OK)
        rc = copy_reply(clnt, reply);
    if (rc == LN_OK)
        request_gen = clnt->conn_gen;
    pthread_mutex_unlock(&clnt->request_lock);
    return rc;
}

/* ---- open / close ---------------------------------------------------------------------- */

/* A lost manager host sends nothing: probe an idle connection (as the manager does its side),
 * so that the monitor notices within about 15 s.  Best effort. */
static void keepalive(int fd)
{
    int on = 1, idle = 5, interval = 2, count = 5;
    unsigned user_timeout_ms = 15000;
    setsockopt(fd, SOL_SOCKET, SO_KEEPALIVE, &on, sizeof on);
    setsockopt(fd, IPPROTO_TCP, TCP_KEEPIDLE, &idle, sizeof idle);
    setsockopt(fd, IPPROTO_TCP, TCP_KEEPINTVL, &interval, sizeof interval);
    setsockopt(fd, IPPROTO_TCP, TCP_KEEPCNT, &count, sizeof count);
    setsockopt(fd, IPPROTO_TCP, TCP_USER_TIMEOUT, &user_timeout_ms, sizeof user_timeout_ms);
}

/* Resolves and connects to the manager into *fd; LN_OK or a recorded error. */
static int connect_manager(ln_client* c, const char* from, const struct timespec* deadline, int* fd)
{
    char what[MAX_ADDRESS + 64];
    snprintf(what, sizeof what, "cannot connect to manager %s%s", c->address, from);
    struct addrinfo* ai = NULL;
    int rc = LN_OK, gai = ln_net_resolve(c->host, c->port, &ai);
    if (gai == EAI_SYSTEM)
        rc = ln_set_errno_error(c, errno, "%s", what);
    else if (gai != 0)
        rc = ln_set_error(c, gai == EAI_MEMORY ? LN_ENOMEM : LN_ECONNECTION, "%s: %s", what,
                          gai_strerror(gai));
    int err = rc == LN_OK ? ln_net_connect(ai, deadline, c->cancel_fd, fd) : 0;
    if (ai != NULL)
        freeaddrinfo(ai);
    if (err != 0)
        rc = io_error(c, err, what);
    if (rc == LN_OK)
        keepalive(*fd);
    return rc;
}

static void conn_init(struct ln_conn* k)
{
    memset(k, 0, sizeof *k);
    k->fd = -1;
    ln_wbuf_init(&k->tx);
}

static void conn_free(struct ln_conn* k)
{
    ln_auth_wipe(k->session_key, sizeof k->session_key);
    k->has_session_key = 0;
    if (k->fd >= 0)
        close(k->fd);
    k->fd = -1;
    k->usable = 0;
    ln_wbuf_free(&k->tx);
    free(k->rx);
    k->rx = NULL;
    k->rx_cap = 0;
}

int ln_conn_open(ln_client* c, const char* from, const char* name)
{
    conn_init(&c->conn);
    struct timespec ts;
    const struct timespec* deadline = ln_net_deadline(&ts, c->timeout);
    int rc = connect_manager(c, from, deadline, &c->conn.fd);
    if (rc == LN_OK)
        rc = handshake(c, &c->conn, name, 0, deadline);
    if (rc != LN_OK) {
        disconnect(c, &c->conn); /* no monitor yet: really closes */
        return rc;
    }
    c->conn.usable = 1;
    c->conn_gen = 1;
    return LN_OK;
}

/* ---- the reconnect monitor -------------------------------------------------------------
 * One thread per client.  While the connection is up it sleeps in poll() on the socket for
 * a hang-up only (POLLRDHUP: the manager never sends unasked, and answers are read by the
 * requesting thread), so it costs nothing.  When the connection is gone it closes the socket
 * and reconnects with back-off.  It says HELLO and re-registers every port and provider on
 * a connection of its own, holding the ports lock (so no port comes or goes meanwhile) but
 * not the request lock: requests of other threads fail fast with LN_ECONNECTION until the
 * new connection is complete and installed. */

#define BACKOFF_FIRST 0.05 /* seconds before the second attempt */
#define BACKOFF_MAX 1.0

static int cancelled(ln_client* c)
{
    struct pollfd pfd = {.fd = c->cancel_fd, .events = POLLIN, .revents = 0};
    return poll(&pfd, 1, 0) > 0;
}

/* Sleeps `seconds` unless cancelled first (then 1). */
static int pause_or_cancel(ln_client* c, double seconds)
{
    struct pollfd pfd = {.fd = c->cancel_fd, .events = POLLIN, .revents = 0};
    int n;
    do
        n = poll(&pfd, 1, (int)(seconds * 1000));
    while (n < 0 && errno == EINTR);
    return n > 0;
}

/* Waits until connection `fd` hangs up (0) or the client is destroyed (1). */
static int watch(ln_client* c, int fd)
{
    struct pollfd pfd[2] = {{.fd = fd, .events = POLLRDHUP, .revents = 0},
                            {.fd = c->cancel_fd, .events = POLLIN, .revents = 0}};
    for (;;) {
        int n = poll(pfd, 2, -1);
        if (n < 0 && errno == EINTR)
            continue;
        if (n < 0 || pfd[1].revents)
            return n < 0 ? 0 : 1;
        if (pfd[0].revents)
            return 0;
    }
}

/* One attempt: connect, HELLO, re-register everything, make the connection the client's. */
static int reconnect_once(ln_client* c)
{
    struct timespec ts;
    const struct timespec* deadline = ln_net_deadline(&ts, c->timeout);
    struct ln_conn fresh;
    conn_init(&fresh);
    int rc = connect_manager(c, "", deadline, &fresh.fd);
    if (rc == LN_OK)
        rc = handshake(c, &fresh, c->name, LN_PROTO_HELLO_RECONNECT, deadline);
    if (rc != LN_OK) {
        conn_free(&fresh);
        return rc;
    }
    fresh.usable = 1;
    pthread_mutex_lock(&c->ports_lock);
    c->reclaim_conn = &fresh;
    /* Ports are re-registered one by one; a refusal is that port's (recorded, the others go
     * on), a broken connection ends the attempt. */
    for (size_t i = 0; i < c->nports && !fresh.broken; i++)
        c->ports[i].ops->reclaim(c, c->ports[i].port);
    c->reclaim_conn = NULL;
    if (fresh.broken) {
        pthread_mutex_unlock(&c->ports_lock);
        conn_free(&fresh);
        return LN_ECONNECTION;
    }
    pthread_mutex_lock(&c->request_lock);
    struct ln_conn old = c->conn;
    c->conn = fresh;
    c->conn_gen++;
    pthread_mutex_unlock(&c->request_lock);
    pthread_mutex_unlock(&c->ports_lock);
    conn_free(&old);
    return LN_OK;
}

static void* monitor_main(void* arg)
{
    ln_client* c = arg;
    for (;;) {
        pthread_mutex_lock(&c->request_lock);
        int fd = c->conn.fd, up = c->conn.usable;
        pthread_mutex_unlock(&c->request_lock);
        if (fd >= 0 && up && watch(c, fd))
            return NULL;
        pthread_mutex_lock(&c->request_lock);
        if (c->conn.fd >= 0)
            close(c->conn.fd);
        c->conn.fd = -1;
        c->conn.usable = 0;
        c->conn.stale_answers = 0;
        pthread_mutex_unlock(&c->request_lock);
        for (double delay = BACKOFF_FIRST; reconnect_once(c) != LN_OK;) {
            if (pause_or_cancel(c, delay))
                return NULL;
            delay = delay * 2 < BACKOFF_MAX ? delay * 2 : BACKOFF_MAX;
        }
        if (cancelled(c))
            return NULL;
    }
}

int ln_conn_start_monitor(ln_client* c)
{
    c->cancel_fd = eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
    if (c->cancel_fd < 0)
        return ln_set_errno_error(c, errno, "cannot create the reconnect monitor's eventfd");
    pthread_mutex_lock(&c->request_lock);
    c->monitored = 1;
    pthread_mutex_unlock(&c->request_lock);
    int err = pthread_create(&c->monitor, NULL, monitor_main, c);
    if (err != 0) {
        c->monitored = 0;
        close(c->cancel_fd);
        c->cancel_fd = -1;
        return ln_set_errno_error(c, err, "cannot start the reconnect monitor thread");
    }
    return LN_OK;
}

void ln_conn_stop_monitor(ln_client* c)
{
    if (!c->monitored)
        return;
    if (getpid() != c->pid) { /* a forked child: the monitor thread is its parent's */
        c->monitored = 0;
        return;
    }
    uint64_t one = 1;
    ssize_t n = write(c->cancel_fd, &one, sizeof one);
    (void)n; /* an eventfd write of 1 cannot fail short of overflow */
    pthread_join(c->monitor, NULL);
    pthread_mutex_lock(&c->request_lock);
    c->monitored = 0;
    if (c->conn.fd >= 0 && !c->conn.usable) { /* shut down, never replaced */
        close(c->conn.fd);
        c->conn.fd = -1;
    }
    /* The requests that close the ports go out normally again. */
    uint64_t count;
    n = read(c->cancel_fd, &count, sizeof count);
    (void)n;
    pthread_mutex_unlock(&c->request_lock);
}

void ln_conn_close(ln_client* c)
{
    c->monitored = 0;
    conn_free(&c->conn);
    if (c->cancel_fd >= 0)
        close(c->cancel_fd);
    c->cancel_fd = -1;
}
