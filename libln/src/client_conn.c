/* client_conn.c — the client's TCP connection to its manager: the HELLO/WELCOME handshake
 * and serialized request/answer round trips (docs/protocol.md).  Failures are recorded with
 * the manager's address and the request; a connection that can no longer be trusted to be
 * in step with the manager is closed for good. */
#include <assert.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "client_conn.h"
#include "net.h"

#define MAX_ADDRESS LN_CLIENT_MAX_ADDRESS

static void disconnect(ln_client* c)
{
    if (c->fd >= 0)
        close(c->fd);
    c->fd = -1;
    c->stale_answers = 0;
}

/* Records a failed transfer (errno value, ETIMEDOUT or LN_NET_EOF) with context `what`. */
static int io_error(ln_client* c, int err, const char* what)
{
    if (err == LN_NET_EOF)
        return ln_set_error(c, LN_ECONNECTION, "%s: manager closed the connection", what);
    if (err == ETIMEDOUT && c->timeout >= 0)
        return ln_set_error(c, LN_ETIMEOUT, "%s: timed out after %g s", what, c->timeout);
    return ln_set_errno_error(c, err, "%s", what);
}

static int malformed(ln_client* c, const char* request, const char* why)
{
    disconnect(c);
    return ln_set_error(c, LN_EPROTOCOL,
                        "malformed answer from manager %s to %s (%s); connection closed",
                        c->address, request, why);
}

static int unexpected(ln_client* c, const char* request, uint16_t type)
{
    char why[64];
    snprintf(why, sizeof why, "unexpected %s frame", ln_proto_type_name(type));
    return malformed(c, request, why);
}

/* Sends the frames in c->tx; any failure leaves half a frame behind, so it disconnects. */
static int send_tx(ln_client* c, const char* request, const struct timespec* deadline)
{
    int err = ln_net_write_all(c->fd, c->tx.data, c->tx.len, deadline);
    if (err == 0)
        return LN_OK;
    char what[MAX_ADDRESS + 64];
    snprintf(what, sizeof what, "cannot send %s to manager %s", request, c->address);
    disconnect(c);
    return io_error(c, err, what);
}

/* Reads one frame into c->rx.  A timeout before its first byte keeps the connection (the
 * answer may still come and is then skipped); every other failure closes it. */
static int read_frame(ln_client* c, const char* request, const struct timespec* deadline,
                      uint16_t* type, ln_rbuf* body)
{
    char what[MAX_ADDRESS + 64];
    snprintf(what, sizeof what, "no answer from manager %s to %s", c->address, request);
    int err = ln_net_wait_readable(c->fd, deadline);
    if (err == ETIMEDOUT)
        return io_error(c, err, what);
    uint8_t header[LN_PROTO_HEADER_SIZE];
    uint32_t len = 0;
    if (err == 0)
        err = ln_net_read_all(c->fd, header, sizeof header, deadline);
    if (err == 0 && ln_proto_parse_header(header, &len, type) != LN_OK) {
        ln_rbuf r;
        ln_rbuf_init(&r, header, sizeof header);
        char why[64];
        uint32_t length = ln_rbuf_u32(&r);
        snprintf(why, sizeof why, "frame length %u, type %u", (unsigned)length,
                 (unsigned)ln_rbuf_u16(&r));
        return malformed(c, request, why);
    }
    if (err == 0 && len > c->rx_cap) {
        uint8_t* rx = realloc(c->rx, len);
        if (rx == NULL) {
            err = ENOMEM;
        } else {
            c->rx = rx;
            c->rx_cap = len;
        }
    }
    if (err == 0)
        err = ln_net_read_all(c->fd, c->rx, len, deadline);
    if (err != 0) {
        disconnect(c);
        return io_error(c, err, what);
    }
    ln_rbuf_init(body, c->rx, len);
    if (!ln_proto_to_client(*type))
        return unexpected(c, request, *type);
    /* A WELCOME of another protocol version may have other fields: handshake() says so. */
    ln_rbuf peek = *body;
    if ((*type != LN_MSG_WELCOME || ln_rbuf_u16(&peek) == LN_PROTO_VERSION)
        && ln_proto_check_fields(*type, body) != LN_OK)
        return malformed(c, request, "fields do not match the frame type");
    return LN_OK;
}

/* The rest of a checked ERROR body (after its request id): records the manager's text behind
 * `prefix` and returns its code. */
static int take_error(ln_client* c, const char* request, ln_rbuf* r, const char* prefix)
{
    int32_t code = ln_rbuf_i32(r);
    char text[LN_PROTO_MAX_STR + 1];
    ln_rbuf_str(r, text, sizeof text);
    if (code >= 0 || code < -LN_ERROR_COUNT) /* well-formed, so the connection stays */
        return ln_set_error(c, LN_EPROTOCOL, "manager %s answered %s with unknown code %d: %s",
                            c->address, request, (int)code, text);
    return ln_set_error(c, code, "%s%s", prefix, text);
}

/* ---- handshake ------------------------------------------------------------------------- */

static int handshake(ln_client* c, const char* name, const struct timespec* deadline)
{
    ln_wbuf_reset(&c->tx);
    size_t start = ln_proto_frame_begin(&c->tx, LN_MSG_HELLO);
    ln_wbuf_u32(&c->tx, LN_PROTO_MAGIC);
    ln_wbuf_u16(&c->tx, LN_PROTO_VERSION);
    ln_wbuf_u32(&c->tx, (uint32_t)c->pid);
    ln_wbuf_str(&c->tx, name);
    ln_wbuf_str(&c->tx, ln_version());
    char host_id[LN_HOST_ID_MAX];
    ln_host_id(host_id, sizeof host_id); /* the manager finds this host's ln_daemon by it */
    ln_wbuf_str(&c->tx, host_id);
    int rc = ln_proto_frame_end(&c->tx, start);
    if (rc != LN_OK)
        return ln_set_error(c, rc, "cannot encode HELLO: %s", ln_strerror(rc));
    rc = send_tx(c, "HELLO", deadline);
    uint16_t type = 0;
    ln_rbuf r;
    if (rc == LN_OK)
        rc = read_frame(c, "HELLO", deadline, &type, &r);
    if (rc != LN_OK)
        return rc;
    if (type == LN_MSG_ERROR) {
        char prefix[MAX_ADDRESS + LN_PROTO_MAX_STR + 64];
        snprintf(prefix, sizeof prefix, "manager %s refused client \"%s\": ", c->address, name);
        if (ln_rbuf_u32(&r) != 0)
            return malformed(c, "HELLO", "ERROR with a request id");
        return take_error(c, "HELLO", &r, prefix);
    }
    if (type != LN_MSG_WELCOME)
        return unexpected(c, "HELLO", type);
    uint16_t version = ln_rbuf_u16(&r);
    if (version != LN_PROTO_VERSION)
        return ln_set_error(c, LN_EVERSION,
                            "manager %s: client speaks protocol %d, manager speaks %u",
                            c->address, LN_PROTO_VERSION, (unsigned)version);
    c->client_id = ln_rbuf_u32(&r);
    ln_rbuf_str(&r, c->name, sizeof c->name);
    ln_rbuf_str(&r, c->instance, sizeof c->instance);
    if (c->name[0] == '\0')
        return malformed(c, "HELLO", "WELCOME with an empty client name");
    return LN_OK;
}

/* ---- requests -------------------------------------------------------------------------- */

/* A PORT_OK for a request that timed out: the manager holds a port nobody knows of, so give
 * it back.  Its OK answer is skipped like any other stale answer. */
static int release_stale_port(ln_client* c, ln_rbuf* r, const struct timespec* deadline)
{
    uint32_t port_id = ln_rbuf_u32(r); /* right after the request id */
    if (++c->last_request_id == 0)
        c->last_request_id = 1;
    ln_wbuf_reset(&c->tx);
    size_t start = ln_proto_frame_begin(&c->tx, LN_MSG_CLOSE_PORT);
    ln_wbuf_u32(&c->tx, c->last_request_id);
    ln_wbuf_u32(&c->tx, port_id);
    int rc = ln_proto_frame_end(&c->tx, start);
    if (rc == LN_OK)
        rc = send_tx(c, "CLOSE_PORT", deadline);
    if (rc == LN_OK)
        c->stale_answers++;
    return rc;
}

static int round_trip(ln_client* c, uint16_t type, const ln_wbuf* body, uint16_t* reply_type,
                      ln_rbuf* reply)
{
    const char* request = ln_proto_type_name(type);
    if (c->fd < 0)
        return ln_set_error(c, LN_ECONNECTION,
                            "cannot send %s: the connection to manager %s was lost earlier",
                            request, c->address);
    if (++c->last_request_id == 0)
        c->last_request_id = 1;
    uint32_t id = c->last_request_id;
    ln_wbuf_reset(&c->tx);
    size_t start = ln_proto_frame_begin(&c->tx, type);
    ln_wbuf_u32(&c->tx, id);
    if (body != NULL)
        ln_wbuf_bytes(&c->tx, body->data, body->len);
    int rc = ln_proto_frame_end(&c->tx, start);
    if (rc != LN_OK)
        return ln_set_error(c, rc, "cannot encode %s: %s", request, ln_strerror(rc));

    struct timespec ts;
    const struct timespec* deadline = ln_net_deadline(&ts, c->timeout);
    rc = send_tx(c, request, deadline);
    uint16_t atype = 0;
    while (rc == LN_OK) {
        rc = read_frame(c, request, deadline, &atype, reply);
        if (rc == LN_ETIMEOUT && c->fd >= 0)
            c->stale_answers++; /* the answer is still due: skip it when it comes */
        if (rc != LN_OK)
            return rc;
        uint32_t answer_id = ln_rbuf_u32(reply); /* every checked answer but WELCOME has one */
        if (atype == LN_MSG_WELCOME)
            return unexpected(c, request, atype);
        if (answer_id == id)
            break;
        if (answer_id == 0 || c->stale_answers == 0)
            return malformed(c, request, "answer to a request that was never sent");
        c->stale_answers--;
        if (atype == LN_MSG_PORT_OK)
            rc = release_stale_port(c, reply, deadline);
    }
    if (rc != LN_OK)
        return rc;
    if (atype == LN_MSG_ERROR)
        return take_error(c, request, reply, "");
    if (atype != ln_proto_answer_type(type))
        return unexpected(c, request, atype);
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

static void reply_key_init(void)
{
    pthread_key_create(&reply_key, reply_free);
}

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

int ln_client_request(ln_client* clnt, uint16_t type, const ln_wbuf* body, uint16_t* reply_type,
                      ln_rbuf* reply)
{
    assert(ln_proto_answer_type(type) != 0 && reply_type != NULL && reply != NULL);
    int rc = ln_client_check(clnt);
    if (rc != LN_OK)
        return rc;
    if (body != NULL && body->failed)
        return ln_set_error(clnt, body->failed, "cannot encode %s: %s", ln_proto_type_name(type),
                            body->failed == LN_EINVAL
                                ? "a text field is NULL, over 1024 bytes or not UTF-8"
                                : ln_strerror(body->failed));
    pthread_mutex_lock(&clnt->request_lock);
    rc = round_trip(clnt, type, body, reply_type, reply);
    if (rc == LN_OK)
        rc = copy_reply(clnt, reply);
    pthread_mutex_unlock(&clnt->request_lock);
    return rc;
}

/* ---- open / close ---------------------------------------------------------------------- */

int ln_conn_open(ln_client* c, const char* host, const char* port, const char* from,
                 const char* name)
{
    char what[MAX_ADDRESS + 64];
    snprintf(what, sizeof what, "cannot connect to manager %s%s", c->address, from);
    struct timespec ts;
    const struct timespec* deadline = ln_net_deadline(&ts, c->timeout);
    struct addrinfo* ai = NULL;
    int rc = LN_OK, gai = ln_net_resolve(host, port, &ai);
    if (gai == EAI_SYSTEM)
        rc = ln_set_errno_error(c, errno, "%s", what);
    else if (gai != 0)
        rc = ln_set_error(c, gai == EAI_MEMORY ? LN_ENOMEM : LN_ECONNECTION, "%s: %s", what,
                          gai_strerror(gai));
    int err = rc == LN_OK ? ln_net_connect(ai, deadline, &c->fd) : 0;
    if (ai != NULL)
        freeaddrinfo(ai);
    if (err != 0)
        rc = io_error(c, err, what);
    if (rc == LN_OK)
        rc = handshake(c, name, deadline);
    if (rc != LN_OK)
        disconnect(c);
    return rc;
}

void ln_conn_close(ln_client* c)
{
    disconnect(c);
    ln_wbuf_free(&c->tx);
    free(c->rx);
    c->rx = NULL;
    c->rx_cap = 0;
}
