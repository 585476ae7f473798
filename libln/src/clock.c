/* clock.c — ln_now(): CLOCK_REALTIME, or the replay clock an ln_play --clock publishes
 * (md ln/clock, docs/recording.md "Replay control and the replay clock") once
 * ln_client_use_clock() asked for it.  ln_now never blocks and never allocates: it takes the
 * newest clock sample with a non-blocking read when no other thread is doing so, and
 * extrapolates the snapshot of the last one with its rate. */
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "client_conn.h"
#include "client_internal.h"
#include "clock_messages.h"
#include "ln/ln.h"

#define DEFAULT_TOPIC "ln.clock"

/* Snapshot protocol: two slots, each with a sequence count (odd while written).  One writer
 * at a time (the thread that won `updating`) writes the slot that is not `current`, then makes
 * it current (release).  A reader copies the current slot between two loads of its count and
 * retries if the count was odd or changed, which needs the writer to have written twice
 * during the copy; a writer stalled in the middle of a write never holds a reader up, since
 * it writes the other slot.  The fields are relaxed atomics: a torn copy is a retry, never a
 * data race. */
struct slot {
    _Atomic uint32_t seq;
    _Atomic int64_t time_ns, stamp_ns;
    _Atomic uint64_t rate_bits; /* the double's bits */
    _Atomic uint32_t epoch;
    _Atomic uint32_t state; /* 0: no sample yet, 1: running, 2: paused */
};

struct ln_replay_clock {
    ln_client* clnt;
    ln_inport* port;
    char topic[LN_PROTO_MAX_STR + 1];
    atomic_flag updating;
    _Atomic uint32_t current;
    struct slot slots[2];
};

typedef struct snapshot {
    int64_t time_ns, stamp_ns;
    double rate;
    uint32_t epoch, state;
} snapshot;

static int64_t realtime_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    return (int64_t)ts.tv_sec * 1000000000 + ts.tv_nsec;
}

static snapshot load(struct ln_replay_clock* c)
{
    snapshot s;
    for (;;) {
        struct slot* sl = &c->slots[atomic_load_explicit(&c->current, memory_order_acquire)];
        uint32_t before = atomic_load_explicit(&sl->seq, memory_order_acquire);
        s.time_ns = atomic_load_explicit(&sl->time_ns, memory_order_relaxed);
        s.stamp_ns = atomic_load_explicit(&sl->stamp_ns, memory_order_relaxed);
        uint64_t bits = atomic_load_explicit(&sl->rate_bits, memory_order_relaxed);
        s.epoch = atomic_load_explicit(&sl->epoch, memory_order_relaxed);
        s.state = atomic_load_explicit(&sl->state, memory_order_relaxed);
        atomic_thread_fence(memory_order_acquire);
        if ((before & 1u) == 0 && atomic_load_explicit(&sl->seq, memory_order_relaxed) == before) {
            memcpy(&s.rate, &bits, sizeof s.rate);
            return s;
        }
    }
}

static void store(struct ln_replay_clock* c, const snapshot* s)
{
    uint32_t next = 1u - atomic_load_explicit(&c->current, memory_order_relaxed);
    struct slot* sl = &c->slots[next];
    uint32_t seq = atomic_load_explicit(&sl->seq, memory_order_relaxed);
    atomic_store_explicit(&sl->seq, seq + 1, memory_order_relaxed);
    atomic_thread_fence(memory_order_release);
    uint64_t bits;
    memcpy(&bits, &s->rate, sizeof bits);
    atomic_store_explicit(&sl->time_ns, s->time_ns, memory_order_relaxed);
    atomic_store_explicit(&sl->stamp_ns, s->stamp_ns, memory_order_relaxed);
    atomic_store_explicit(&sl->rate_bits, bits, memory_order_relaxed);
    atomic_store_explicit(&sl->epoch, s->epoch, memory_order_relaxed);
    atomic_store_explicit(&sl->state, s->state, memory_order_relaxed);
    atomic_store_explicit(&sl->seq, seq + 2, memory_order_release);
    atomic_store_explicit(&c->current, next, memory_order_release);
}

static int64_t at(const snapshot* s, int64_t now)
{
    if (s->state != 1)
        return s->time_ns;
    return s->time_ns + (int64_t)((double)(now - s->stamp_ns) * s->rate);
}

/* Takes the newest clock sample, if any came and no other thread is taking it.  Within one
 * epoch the new base never lies below the old one's extrapolation at its stamp, so the
 * jitter between samples cannot make the time step back. */
static void update(struct ln_replay_clock* c)
{
    if (atomic_flag_test_and_set_explicit(&c->updating, memory_order_acquire))
        return;
    ln_clock_t msg;
    if (ln_read(c->port, &msg, sizeof msg, 0.0, NULL) == LN_OK) {
        snapshot old = load(c);
        snapshot s = {msg.time_ns, msg.stamp_ns, msg.rate > 0 ? msg.rate : 1.0, msg.epoch,
                      msg.paused ? 2u : 1u};
        if (old.state == 1 && s.state == 1 && old.epoch == s.epoch) {
            int64_t floor = at(&old, s.stamp_ns);
            if (s.time_ns < floor)
                s.time_ns = floor;
        }
        store(c, &s);
    }
    atomic_flag_clear_explicit(&c->updating, memory_order_release);
}

static void clock_close_fn(void* p)
{
    struct ln_replay_clock* c = p;
    atomic_store(&c->clnt->clock, NULL);
    ln_unsubscribe(c->port);
    ln_client_remove_port(c->clnt, c);
    free(c);
}

static int clock_reclaim(ln_client* clnt, void* c)
{
    (void)clnt;
    (void)c;
    return LN_OK; /* its subscription registers itself again */
}

static const ln_client_port_ops clock_ops = {clock_close_fn, clock_reclaim};

int ln_client_use_clock(ln_client* clnt, const char* topic)
{
    int rc = ln_client_check(clnt);
    if (rc != LN_OK)
        return rc;
    if (topic == NULL)
        topic = DEFAULT_TOPIC;
    if (strlen(topic) > LN_PROTO_MAX_STR)
        return ln_set_error(clnt, LN_EINVAL, "ln_client_use_clock: topic name too long");
    struct ln_replay_clock* have = atomic_load(&clnt->clock);
    if (have != NULL) {
        if (strcmp(have->topic, topic) == 0)
            return LN_OK;
        return ln_set_error(clnt, LN_EEXIST,
                            "ln_client_use_clock: the client follows clock "
                            "topic '%s' already, not '%s'",
                            have->topic, topic);
    }
    struct ln_replay_clock* c = calloc(1, sizeof *c);
    if (c == NULL)
        return ln_set_error(clnt, LN_ENOMEM, "ln_client_use_clock: out of memory");
    c->clnt = clnt;
    atomic_flag_clear(&c->updating);
    strcpy(c->topic, topic);
    ln_port_options opts;
    ln_port_options_init(&opts);
    opts.spin_us = 0;
    rc = ln_subscribe(clnt, &c->port, topic, LN_CLOCK_MD_NAME, LN_CLOCK_LAYOUT_HASH,
                      sizeof(ln_clock_t), &opts);
    if (rc != LN_OK)
        goto fail;
    rc = ln_client_add_port(clnt, c, &clock_ops, 0);
    if (rc != LN_OK)
        goto fail;
    atomic_store(&clnt->clock, c);
    return LN_OK;
fail:
    if (c->port != NULL)
        ln_unsubscribe(c->port);
    free(c);
    return rc;
}

int ln_now(ln_client* clnt, int64_t* ns)
{
    int rc = ln_client_check(clnt);
    if (rc != LN_OK)
        return rc;
    if (ns == NULL)
        return ln_set_error(clnt, LN_EINVAL, "ln_now: ns must not be NULL");
    int64_t now = realtime_ns();
    struct ln_replay_clock* c = atomic_load_explicit(&clnt->clock, memory_order_acquire);
    if (c == NULL) {
        *ns = now;
        return LN_OK;
    }
    update(c);
    snapshot s = load(c);
    *ns = s.state == 0 ? 0 : at(&s, now);
    return LN_OK;
}
