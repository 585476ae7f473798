/* port.c — publishers (outports) and subscribers (inports): registration with the manager
 * (again after a reconnect: RECLAIM_PORT), mapping the topic ring it names, and the copy and
 * zero-copy write/read paths on it.  A port follows its topic to a bigger ring when the
 * manager retires the old one. */
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bell.h"
#include "client_internal.h"
#include "futex.h"
#include "ring.h"
#include "waitset_internal.h"

#define LN_OUTPORT_MAGIC 0x4c4e4f50u
#define LN_INPORT_MAGIC 0x4c4e4950u
#define LN_NO_READER 0xffffffffu

typedef struct ln_port_common {
    uint32_t magic;
    ln_client* clnt;
    uint64_t layout_hash;
    uint64_t size;
    ln_ring ring;
    char topic[LN_RING_NAME_MAX];
    /* Registration, for RECLAIM_PORT; changed only under the client's ports lock once the
     * port is on its client.  `segment` is the generation the manager last named (the port
     * may have followed it to newer ones), `reader` the reader slot (subscribers). */
    uint16_t kind; /* LN_PROTO_RECLAIM_PUBLISHER or LN_PROTO_RECLAIM_SUBSCRIBER */
    uint32_t port_id;
    int registered; /* the manager knows port_id (not after a refused re-registration) */
    uint32_t buffers, flags, reader;
    char md_name[LN_RING_NAME_MAX];
    char segment[LN_RING_NAME_MAX];
} ln_port_common;

struct ln_outport {
    ln_port_common c;
    uint32_t flags;
    uint32_t spin_us; /* waiting for subscribers: poll before sleeping */
    ln_ring_slot* loan;
    pthread_t loan_thread; /* the write lock belongs to the thread that took the loan */
};

struct ln_inport {
    ln_port_common c;
    ln_ring_cursor cur;
    uint32_t spin_us;
    ln_ring_slot* borrowed;
    uint64_t borrowed_word;
    ln_waitset* ws; /* the waitset it is attached to (waitset.c; its id: cur.bell_tag) */
};

void ln_port_options_init(ln_port_options* opts)
{
    if (opts) {
        opts->buffers = 1;
        opts->flags = 0;
        opts->spin_us = LN_DEFAULT_SPIN_US;
    }
}

static int bad_port(const void* port, uint32_t magic, const char* what)
{
    if (!port || *(const uint32_t*)port != magic)
        return ln_set_error(NULL, LN_EBADHANDLE, "%s: invalid or closed port handle", what);
    return LN_OK;
}

/* Failures inside the ring are recorded per thread; keep them on the client as well. */
static int on_client(ln_port_common* p, int rc)
{
    if (rc < 0 && rc != LN_EAGAIN)
        ln_client_store_error(p->clnt, rc, ln_last_error());
    return rc;
}

/* Move to the newest generation (publishers: they only ever write the newest ring). */
static int follow(ln_port_common* p) { return on_client(p, ln_ring_follow(&p->ring)); }

/* NaN is the one timeout that means nothing. */
static int check_timeout(ln_client* clnt, double timeout, const char* what)
{
    if (isnan(timeout))
        return ln_set_error(clnt, LN_EINVAL, "%s: timeout is NaN", what);
    return LN_OK;
}

static int close_remote(ln_port_common* p)
{
    if (!p->registered)
        return LN_OK; /* the manager does not know it */
    ln_wbuf body;
    ln_rbuf reply;
    uint16_t type = 0;
    ln_wbuf_init(&body);
    ln_msg_close_port close = {.port_id = p->port_id};
    ln_msg_close_port_write_after_id(&body, &close);
    int rc = ln_client_request(p->clnt, LN_MSG_CLOSE_PORT, &body, &type, &reply);
    ln_wbuf_free(&body);
    if (rc == LN_OK && (type != LN_MSG_OK || ln_rbuf_end(&reply) != LN_OK))
        rc = ln_set_error(p->clnt, LN_EPROTOCOL, "unexpected answer %u to CLOSE_PORT", type);
    return rc;
}

/* The flags of one kind of port: LN_PUBLISH_* for publishers, at most one LN_SUBSCRIBE_*
 * transport for subscribers. */
static int check_flags(ln_client* clnt, uint16_t msg, uint32_t flags)
{
    const uint32_t transports = LN_SUBSCRIBE_UDP | LN_SUBSCRIBE_TCP;
    if (msg == LN_MSG_PUBLISH && (flags & transports))
        return ln_set_error(clnt, LN_EINVAL,
                            "ln_publish: flags 0x%x hold LN_SUBSCRIBE_* bits, "
                            "which only subscribers take",
                            flags);
    if (msg == LN_MSG_SUBSCRIBE && (flags & LN_PUBLISH_WAIT_FOR_SUBSCRIBERS))
        return ln_set_error(clnt, LN_EINVAL,
                            "ln_subscribe: LN_PUBLISH_WAIT_FOR_SUBSCRIBERS is a "
                            "publisher flag");
    if ((flags & transports) == transports)
        return ln_set_error(clnt, LN_EINVAL,
                            "ln_subscribe: LN_SUBSCRIBE_UDP and "
                            "LN_SUBSCRIBE_TCP together; choose one transport");
    return LN_OK;
}

/* Register a port with the manager and map the ring it names. */
static int open_port(ln_port_common* p, ln_client* clnt, uint16_t msg, const char* topic,
                     const char* md_name, uint64_t hash, size_t size, const ln_port_options* o,
                     uint32_t* reader_index, uint64_t* gen)
{
    ln_port_options defaults;
    if (!o) {
        ln_port_options_init(&defaults);
        o = &defaults;
    }
    int rc = ln_client_check(clnt);
    if (rc != LN_OK)
        return ln_set_error(NULL, rc, "invalid client handle");
    if (!topic || !md_name || size == 0 || size > UINT32_MAX)
        return ln_set_error(clnt, LN_EINVAL,
                            "%s: topic and md name are required, size must be "
                            "1..4 GiB",
                            msg == LN_MSG_PUBLISH ? "ln_publish" : "ln_subscribe");
    if (strlen(topic) >= sizeof(p->topic) || strlen(md_name) >= sizeof(p->md_name))
        return ln_set_error(clnt, LN_EINVAL, "topic or md name longer than %zu bytes",
                            sizeof(p->topic) - 1);
    if ((rc = check_flags(clnt, msg, o->flags)) != LN_OK)
        return rc;
    ln_wbuf body;
    ln_rbuf reply;
    uint16_t type = 0;
    char segment[LN_RING_NAME_MAX];
    ln_wbuf_init(&body);
    if (msg == LN_MSG_PUBLISH) {
        ln_msg_publish m = {.topic = ln_strv_of(topic),
                            .md_name = ln_strv_of(md_name),
                            .layout_hash = hash,
                            .message_size = (uint32_t)size,
                            .buffers = o->buffers,
                            .flags = o->flags};
        ln_msg_publish_write_after_id(&body, &m);
    } else {
        ln_msg_subscribe m = {.topic = ln_strv_of(topic),
                              .md_name = ln_strv_of(md_name),
                              .layout_hash = hash,
                              .message_size = (uint32_t)size,
                              .buffers = o->buffers,
                              .flags = o->flags};
        ln_msg_subscribe_write_after_id(&body, &m);
    }
    rc = ln_client_request(clnt, msg, &body, &type, &reply);
    ln_wbuf_free(&body);
    if (rc != LN_OK)
        return rc;
    *gen = ln_client_request_gen();
    ln_msg_port_ok ok;
    if (type != LN_MSG_PORT_OK || ln_msg_port_ok_read_after_id(&reply, &ok) != LN_OK ||
        ln_strv_copy(ok.segment, segment, sizeof segment) != LN_OK)
        return ln_set_error(clnt, LN_EPROTOCOL, "unexpected answer %u to a port request", type);
    p->port_id = ok.port_id;
    *reader_index = ok.reader_index;
    p->clnt = clnt;
    p->layout_hash = hash;
    p->size = size;
    p->registered = 1;
    p->kind = msg == LN_MSG_PUBLISH ? LN_PROTO_RECLAIM_PUBLISHER : LN_PROTO_RECLAIM_SUBSCRIBER;
    p->buffers = o->buffers;
    p->flags = o->flags;
    p->reader = *reader_index;
    snprintf(p->topic, sizeof(p->topic), "%s", topic);
    snprintf(p->md_name, sizeof(p->md_name), "%s", md_name);
    snprintf(p->segment, sizeof(p->segment), "%s", segment);
    rc = ln_ring_attach(&p->ring, segment, hash, size);
    if (rc == LN_OK)
        rc = follow(p);
    if (rc != LN_OK) {
        char why[512];
        snprintf(why, sizeof(why), "%s", ln_last_error());
        ln_ring_detach(&p->ring);
        close_remote(p);
        return ln_set_error(clnt, rc, "topic '%s': %s", topic, why);
    }
    return LN_OK;
}

static int close_port(ln_port_common* p);

static void close_outport(void* port) { ln_unpublish(port); }

static void close_inport(void* port) { ln_unsubscribe(port); }

/* After a reconnect (ports and request locks held): tell the new manager about the port and
 * the ring and reader slot it uses, so that it adopts them instead of making new ones.  A
 * refusal leaves the port on its ring, working with every port that shares it, but unknown
 * to the manager: ports made later get another ring.  That is recorded as the client's last
 * error; the next reconnect tries again. */
static int reclaim_port(ln_client* clnt, void* port)
{
    ln_port_common* p = port;
    ln_wbuf body;
    ln_rbuf reply;
    uint16_t type = 0;
    ln_wbuf_init(&body);
    ln_msg_reclaim_port m = {.kind = p->kind,
                             .topic = ln_strv_of(p->topic),
                             .md_name = ln_strv_of(p->md_name),
                             .layout_hash = p->layout_hash,
                             .message_size = (uint32_t)p->size,
                             .buffers = p->buffers,
                             .flags = p->flags,
                             .segment = ln_strv_of(p->segment),
                             .reader_index = p->reader};
    ln_msg_reclaim_port_write_after_id(&body, &m);
    int rc = ln_client_request_locked(clnt, LN_MSG_RECLAIM_PORT, &body, &type, &reply);
    ln_wbuf_free(&body);
    const char* what = p->kind == LN_PROTO_RECLAIM_PUBLISHER ? "publisher" : "subscriber";
    p->registered = 0;
    if (rc != LN_OK)
        return ln_set_error(clnt, rc,
                            "topic '%s': the manager refused to take back this "
                            "client's %s on %s (it keeps working on that ring, unknown to the "
                            "manager): %s",
                            p->topic, what, p->segment, ln_last_error());
    char segment[LN_RING_NAME_MAX];
    ln_msg_port_ok ok = {0};
    if (ln_msg_port_ok_read_after_id(&reply, &ok) != LN_OK ||
        ln_strv_copy(ok.segment, segment, sizeof segment) != LN_OK || ok.reader_index != p->reader)
        return ln_set_error(clnt, LN_EPROTOCOL,
                            "topic '%s': the manager took back the %s with "
                            "reader slot %u instead of %u",
                            p->topic, what, ok.reader_index, p->reader);
    p->port_id = ok.port_id;
    p->registered = 1;
    memcpy(p->segment, segment, sizeof p->segment);
    return LN_OK;
}

static const ln_client_port_ops outport_ops = {close_outport, reclaim_port};
static const ln_client_port_ops inport_ops = {close_inport, reclaim_port};

/* Allocate a port of `size` bytes (an ln_port_common first) and register it with the
 * manager; NULL with *rc set on failure. */
static ln_port_common* new_port(ln_client* clnt, size_t size, uint16_t msg, const char* topic,
                                const char* md_name, uint64_t hash, size_t message_size,
                                const ln_port_options* opts, uint32_t* reader, uint64_t* gen,
                                int* rc)
{
    ln_port_common* p = calloc(1, size);
    if (!p) {
        *rc = ln_set_error(clnt, LN_ENOMEM, "out of memory");
        return NULL;
    }
    *rc = open_port(p, clnt, msg, topic, md_name, hash, message_size, opts, reader, gen);
    if (*rc != LN_OK) {
        free(p);
        return NULL;
    }
    return p;
}

/* Make a set-up port usable and hand it to its client, which closes it on destroy and
 * re-registers it after a reconnect. */
static int adopt_port(ln_port_common* p, uint32_t magic, const ln_client_port_ops* ops,
                      uint64_t gen)
{
    ln_client* clnt = p->clnt;
    p->magic = magic;
    int rc = ln_client_add_port(clnt, p, ops, gen);
    if (rc != LN_OK) {
        close_remote(p);
        ln_ring_detach(&p->ring);
        p->magic = 0;
        free(p);
        return ln_set_error(clnt, rc, "out of memory");
    }
    return LN_OK;
}

int ln_publish(ln_client* clnt, ln_outport** out, const char* topic, const char* md_name,
               uint64_t layout_hash, size_t message_size, const ln_port_options* opts)
{
    if (!out)
        return ln_set_error(clnt, LN_EINVAL, "ln_publish: out is NULL");
    *out = NULL;
    uint32_t reader = 0;
    uint64_t gen = 0;
    int rc;
    ln_outport* p = (ln_outport*)new_port(clnt, sizeof(ln_outport), LN_MSG_PUBLISH, topic, md_name,
                                          layout_hash, message_size, opts, &reader, &gen, &rc);
    if (!p)
        return rc;
    p->flags = opts ? opts->flags : 0;
    p->spin_us = opts ? opts->spin_us : LN_DEFAULT_SPIN_US;
    if ((rc = adopt_port(&p->c, LN_OUTPORT_MAGIC, &outport_ops, gen)) == LN_OK)
        *out = p;
    return rc;
}

int ln_subscribe(ln_client* clnt, ln_inport** out, const char* topic, const char* md_name,
                 uint64_t layout_hash, size_t message_size, const ln_port_options* opts)
{
    if (!out)
        return ln_set_error(clnt, LN_EINVAL, "ln_subscribe: out is NULL");
    *out = NULL;
    uint32_t reader = 0;
    uint64_t gen = 0;
    int rc;
    ln_inport* p = (ln_inport*)new_port(clnt, sizeof(ln_inport), LN_MSG_SUBSCRIBE, topic, md_name,
                                        layout_hash, message_size, opts, &reader, &gen, &rc);
    if (!p)
        return rc;
    p->cur.buffers = opts && opts->buffers > 1 ? opts->buffers : 1;
    p->spin_us = opts ? opts->spin_us : LN_DEFAULT_SPIN_US;
    p->cur.reader = reader == LN_NO_READER || reader >= LN_RING_MAX_READERS ? -1 : (int)reader;
    if (p->cur.buffers > 1 && p->cur.reader >= 0)
        p->cur.next = atomic_load(&p->c.ring.hdr->readers[p->cur.reader].next_seq);
    else
        p->cur.next = 1; /* latest: the first read returns the newest sample there is */
    ln_ring_publish_cursor(&p->c.ring, &p->cur); /* hot slots: keep the newest for it */
    if ((rc = adopt_port(&p->c, LN_INPORT_MAGIC, &inport_ops, gen)) == LN_OK)
        *out = p;
    return rc;
}

static int close_port(ln_port_common* p)
{
    /* Off the client first: that waits for a re-registration in progress, and from then on
     * port_id is ours alone. */
    ln_client_remove_port(p->clnt, p);
    int rc = close_remote(p); /* the manager also releases it when the connection is gone */
    ln_ring_detach(&p->ring);
    p->magic = 0;
    free(p);
    return rc == LN_ECONNECTION ? LN_OK : rc;
}

int ln_unpublish(ln_outport* port)
{
    int rc = bad_port(port, LN_OUTPORT_MAGIC, "ln_unpublish");
    if (rc != LN_OK)
        return rc;
    if (port->loan && (rc = ln_write_abort(port)) != LN_OK)
        return rc; /* unmapping under another thread's loan would wedge the topic's lock */
    return close_port(&port->c);
}

int ln_unsubscribe(ln_inport* port)
{
    int rc = bad_port(port, LN_INPORT_MAGIC, "ln_unsubscribe");
    if (rc != LN_OK)
        return rc;
    ln_waitset_forget(port->ws, port->cur.bell_tag, port);
    return close_port(&port->c);
}

static int timeout_code(int rc, const ln_deadline* d)
{
    return rc == LN_ETIMEOUT && !d->forever && d->timeout == 0 ? LN_EAGAIN : rc;
}

/* Take the write side of the newest ring; with LN_PUBLISH_WAIT_FOR_SUBSCRIBERS also wait,
 * without holding the lock, until every queued subscriber has room. */
static int begin_write(ln_outport* p, ln_deadline* d, ln_ring_slot** slot)
{
    int spun = 0;
    for (;;) {
        int rc = ln_ring_lock(&p->c.ring, d);
        if (rc != LN_OK)
            return timeout_code(rc, d);
        int retired = atomic_load_explicit(&p->c.ring.hdr->retired, memory_order_acquire);
        if (!retired &&
            (!(p->flags & LN_PUBLISH_WAIT_FOR_SUBSCRIBERS) || ln_ring_has_space(&p->c.ring))) {
            *slot = ln_ring_begin(&p->c.ring);
            return LN_OK;
        }
        ln_ring_unlock(&p->c.ring);
        /* A subscriber that is about to release a buffer frees it without a futex wake-up
         * (a system call on its side, per sample) if the publisher polls a little first. */
        if (!retired && !spun && (d->forever || d->timeout > 0)) {
            spun = 1;
            if (ln_ring_spin_space(&p->c.ring, p->spin_us))
                continue;
        }
        rc = retired ? follow(&p->c) : ln_ring_sleep_for_space(&p->c.ring, d);
        if (rc != LN_OK)
            return timeout_code(rc, d);
    }
}

int ln_write(ln_outport* p, const void* data, size_t size, double timeout)
{
    int rc = bad_port(p, LN_OUTPORT_MAGIC, "ln_write");
    if (rc != LN_OK)
        return rc;
    if (size != p->c.size || !data)
        return ln_set_error(p->c.clnt, LN_EINVAL,
                            "ln_write on '%s': %zu bytes given, messages "
                            "are %llu bytes",
                            p->c.topic, size, (unsigned long long)p->c.size);
    if (p->loan)
        return ln_set_error(p->c.clnt, LN_EBUSY, "ln_write on '%s': a loan is outstanding",
                            p->c.topic);
    if ((rc = check_timeout(p->c.clnt, timeout, "ln_write")) != LN_OK)
        return rc;
    ln_deadline d = ln_deadline_in(timeout);
    ln_ring_slot* slot;
    rc = begin_write(p, &d, &slot);
    if (rc != LN_OK)
        return on_client(&p->c, rc);
    memcpy(ln_ring_payload(slot), data, size);
    ln_ring_commit(&p->c.ring, slot);
    return ln_ring_unlock(&p->c.ring);
}

int ln_write_loan(ln_outport* p, void** data, double timeout)
{
    int rc = bad_port(p, LN_OUTPORT_MAGIC, "ln_write_loan");
    if (rc != LN_OK)
        return rc;
    if (!data)
        return ln_set_error(p->c.clnt, LN_EINVAL, "ln_write_loan: data is NULL");
    if (p->loan)
        return ln_set_error(p->c.clnt, LN_EBUSY, "ln_write_loan on '%s': a loan is outstanding",
                            p->c.topic);
    if ((rc = check_timeout(p->c.clnt, timeout, "ln_write_loan")) != LN_OK)
        return rc;
    ln_deadline d = ln_deadline_in(timeout);
    rc = begin_write(p, &d, &p->loan);
    if (rc != LN_OK)
        return on_client(&p->c, rc);
    p->loan_thread = pthread_self();
    *data = ln_ring_payload(p->loan);
    return LN_OK;
}

/* Commit and abort must come from the thread that holds the write lock. */
static int check_loan(ln_outport* p, const char* what)
{
    if (!p->loan)
        return ln_set_error(p->c.clnt, LN_EINVAL, "%s on '%s': no loan", what, p->c.topic);
    if (!pthread_equal(p->loan_thread, pthread_self()))
        return ln_set_error(p->c.clnt, LN_EBUSY,
                            "%s on '%s': the loan belongs to another "
                            "thread; commit or abort it there",
                            what, p->c.topic);
    return LN_OK;
}

int ln_write_commit(ln_outport* p)
{
    int rc = bad_port(p, LN_OUTPORT_MAGIC, "ln_write_commit");
    if (rc != LN_OK)
        return rc;
    if ((rc = check_loan(p, "ln_write_commit")) != LN_OK)
        return rc;
    ln_ring_commit(&p->c.ring, p->loan);
    p->loan = NULL;
    return ln_ring_unlock(&p->c.ring);
}

int ln_write_abort(ln_outport* p)
{
    int rc = bad_port(p, LN_OUTPORT_MAGIC, "ln_write_abort");
    if (rc != LN_OK)
        return rc;
    if ((rc = check_loan(p, "ln_write_abort")) != LN_OK)
        return rc;
    p->loan = NULL; /* the slot stays WRITING; the next write reuses its sequence number */
    return ln_ring_unlock(&p->c.ring);
}

/* `rc` of a ring read, with the port's wording of a timeout. */
static int read_result(ln_inport* p, int rc, double timeout)
{
    if (rc == LN_ETIMEOUT)
        return ln_set_error(p->c.clnt, LN_ETIMEOUT, "no sample on topic '%s' within %g s",
                            p->c.topic, timeout);
    return rc;
}

/* The next sample for this subscriber (ln_ring_next). */
static int next_sample(ln_inport* p, double timeout, ln_ring_slot** slot, uint64_t* word)
{
    int rc = check_timeout(p->c.clnt, timeout, "ln_read");
    if (rc != LN_OK)
        return rc;
    return read_result(p, ln_ring_next(&p->c.ring, &p->cur, timeout, p->spin_us, slot, word),
                       timeout);
}

static void fill_info(ln_inport* p, uint64_t word, int64_t ts, ln_sample_info* info)
{
    p->cur.total += p->cur.pending;
    if (info) {
        info->seq = LN_SLOT_SEQ(word);
        info->timestamp_ns = ts;
        info->overruns = p->cur.pending;
    }
    p->cur.pending = 0;
}

int ln_read(ln_inport* p, void* data, size_t size, double timeout, ln_sample_info* info)
{
    int rc = bad_port(p, LN_INPORT_MAGIC, "ln_read");
    if (rc != LN_OK)
        return rc;
    if (size != p->c.size || !data)
        return ln_set_error(p->c.clnt, LN_EINVAL,
                            "ln_read on '%s': buffer of %zu bytes, messages "
                            "are %llu bytes",
                            p->c.topic, size, (unsigned long long)p->c.size);
    if (p->borrowed)
        return ln_set_error(p->c.clnt, LN_EBUSY,
                            "ln_read on '%s': a borrowed sample is not "
                            "released",
                            p->c.topic);
    if ((rc = check_timeout(p->c.clnt, timeout, "ln_read")) != LN_OK)
        return rc;
    uint64_t word;
    int64_t ts;
    rc = read_result(
        p, ln_ring_read_copy(&p->c.ring, &p->cur, timeout, p->spin_us, data, &word, &ts), timeout);
    if (rc != LN_OK)
        return on_client(&p->c, rc);
    fill_info(p, word, ts, info);
    return LN_OK;
}

int ln_read_borrow(ln_inport* p, const void** data, double timeout, ln_sample_info* info)
{
    int rc = bad_port(p, LN_INPORT_MAGIC, "ln_read_borrow");
    if (rc != LN_OK)
        return rc;
    if (!data)
        return ln_set_error(p->c.clnt, LN_EINVAL, "ln_read_borrow: data is NULL");
    if (p->borrowed)
        return ln_set_error(p->c.clnt, LN_EBUSY, "ln_read_borrow on '%s': already borrowed",
                            p->c.topic);
    ln_ring_slot* slot;
    uint64_t word;
    rc = next_sample(p, timeout, &slot, &word);
    if (rc != LN_OK)
        return on_client(&p->c, rc);
    p->borrowed = slot;
    p->borrowed_word = word;
    fill_info(p, word, slot->timestamp_ns, info);
    *data = ln_ring_payload(slot);
    return LN_OK;
}

int ln_read_release(ln_inport* p)
{
    int rc = bad_port(p, LN_INPORT_MAGIC, "ln_read_release");
    if (rc != LN_OK)
        return rc;
    if (!p->borrowed)
        return ln_set_error(p->c.clnt, LN_EINVAL, "ln_read_release on '%s': nothing borrowed",
                            p->c.topic);
    rc = ln_ring_finish(&p->c.ring, &p->cur, p->borrowed, p->borrowed_word, 0);
    p->borrowed = NULL;
    if (rc != LN_OK) {
        return ln_set_error(p->c.clnt, LN_EOVERRUN,
                            "topic '%s': sample %llu was overwritten "
                            "while borrowed",
                            p->c.topic, (unsigned long long)LN_SLOT_SEQ(p->borrowed_word));
    }
    return LN_OK;
}

/* The manager keeps the port counts in the newest generation of a topic's ring. */
static int newest_counts(const ln_port_common* p, uint32_t* publishers, uint32_t* subscribers)
{
    const ln_ring_header* h = p->ring.hdr;
    if (!atomic_load_explicit(&h->retired, memory_order_acquire)) {
        *publishers = atomic_load(&h->publishers);
        *subscribers = atomic_load(&h->subscribers);
        return LN_OK;
    }
    ln_port_common peek = *p; /* a private walk along the successors */
    int rc = ln_ring_attach(&peek.ring, p->ring.name, p->layout_hash, p->size);
    if (rc == LN_OK)
        rc = follow(&peek);
    if (rc == LN_OK) {
        *publishers = atomic_load(&peek.ring.hdr->publishers);
        *subscribers = atomic_load(&peek.ring.hdr->subscribers);
    }
    ln_ring_detach(&peek.ring);
    return rc;
}

int ln_outport_subscriber_count(const ln_outport* p)
{
    uint32_t pubs = 0, subs = 0;
    int rc = bad_port(p, LN_OUTPORT_MAGIC, "ln_outport_subscriber_count");
    if (rc == LN_OK)
        rc = newest_counts(&p->c, &pubs, &subs);
    return rc != LN_OK ? rc : (int)subs;
}

int ln_inport_publisher_count(const ln_inport* p)
{
    uint32_t pubs = 0, subs = 0;
    int rc = bad_port(p, LN_INPORT_MAGIC, "ln_inport_publisher_count");
    if (rc == LN_OK)
        rc = newest_counts(&p->c, &pubs, &subs);
    return rc != LN_OK ? rc : (int)pubs;
}

uint64_t ln_inport_overruns(const ln_inport* p)
{
    if (bad_port(p, LN_INPORT_MAGIC, "ln_inport_overruns") != LN_OK)
        return 0;
    return p->cur.total + p->cur.pending; /* pending: found lost, not yet reported by a read */
}

int ln_inport_set_interruptible(ln_inport* p, int on)
{
    int rc = bad_port(p, LN_INPORT_MAGIC, "ln_inport_set_interruptible");
    if (rc == LN_OK)
        p->cur.interruptible = on != 0;
    return rc;
}

int ln_inport_interrupt(ln_inport* p)
{
    int rc = bad_port(p, LN_INPORT_MAGIC, "ln_inport_interrupt");
    if (rc != LN_OK)
        return rc;
    atomic_store_explicit(&p->cur.interrupted, 1, memory_order_seq_cst);
    /* wakes every sleeper of the ring; the others find nothing new and sleep again */
    ln_futex_bump_wake(&p->c.ring.hdr->data_futex);
    return LN_OK;
}

/* ---- for waitset.c (waitset_internal.h) ---- */

int ln_inport_check(const ln_inport* p, const char* what)
{
    return bad_port(p, LN_INPORT_MAGIC, what);
}

int ln_inport_bell(ln_inport* p, ln_waitset* ws, uint32_t id, uint64_t bell)
{
    if (p->cur.reader < 0)
        return ln_set_error(p->c.clnt, LN_EINVAL, "topic '%s': this subscriber has no reader slot",
                            p->c.topic);
    p->ws = ws;
    p->cur.bell = bell;
    p->cur.bell_tag = id;
    ln_ring_set_bell(p->c.ring.hdr, (uint32_t)p->cur.reader, bell, id);
    return LN_OK;
}

ln_waitset* ln_inport_waitset(const ln_inport* p) { return p->ws; }

int ln_inport_ready(ln_inport* p)
{
    /* seen by the writer before the check below, so no sample falls between */
    if (p->cur.reader >= 0)
        atomic_store_explicit(&p->c.ring.hdr->readers[p->cur.reader].bell_pending, 0,
                              memory_order_seq_cst);
    return on_client(&p->c, ln_ring_has_data(&p->c.ring, &p->cur));
}

uint64_t ln_inport_write_seq(const ln_inport* p)
{
    return atomic_load_explicit(&p->c.ring.hdr->write_seq, memory_order_acquire);
}

int ln_inport_live_publishers(const ln_inport* p)
{
    if (atomic_load_explicit(&p->c.ring.hdr->retired, memory_order_acquire))
        return ln_inport_publisher_count(p); /* the successor's, through a look at it */
    return (int)atomic_load_explicit(&p->c.ring.hdr->publishers, memory_order_relaxed);
}
