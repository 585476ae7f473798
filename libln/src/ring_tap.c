/* ring_tap.c — taps: a topic ring mapped without the manager and without a reader slot, for the
 * daemons that forward topics between hosts.  Reading takes samples out like a subscriber
 * that never holds publishers back (copied, or borrowed in place and checked afterwards);
 * injecting writes forwarded samples in under their original sequence numbers and timestamps
 * (the seqlock of ring.h, numbers may jump), copied or filled in place. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "client_internal.h"
#include "ring.h"

#define LN_TAP_MAGIC 0x4c4e5450u
/* How long inject waits for the write lock: another publisher of the topic on this host may
 * hold it with a loan; the daemon's stream must not hang on that. */
#define LN_TAP_LOCK_TIMEOUT 1.0

struct ln_ring_tap {
    uint32_t magic;
    unsigned mode;
    ln_ring ring;
    ln_ring_cursor cur;      /* reading; holds no reader slot (reader = -1) */
    ln_ring_slot* borrowed;  /* the sample of ln_ring_tap_borrow, until released */
    uint64_t borrowed_word;  /* its seq word */
    ln_ring_slot* injecting; /* the slot of ln_ring_tap_inject_begin, until commit/abort */
    uint64_t injecting_seq;
};

static int bad_tap(const ln_ring_tap* t, const char* what)
{
    if (!t || t->magic != LN_TAP_MAGIC)
        return ln_set_error(NULL, LN_EBADHANDLE, "%s: invalid or closed tap handle", what);
    return LN_OK;
}

/* EVERY reads like a queued subscriber with as many buffers as the ring has slots: whatever
 * the ring still holds. */
static void fit_cursor(ln_ring_tap* t)
{
    t->cur.buffers = t->mode == LN_TAP_EVERY ? t->ring.slot_count : 1;
}

int ln_ring_tap_open(ln_ring_tap** out, const char* shm_name, uint64_t layout_hash,
                     uint64_t message_size, unsigned mode)
{
    if (!out)
        return ln_set_error(NULL, LN_EINVAL, "ln_ring_tap_open: out is NULL");
    *out = NULL;
    if (!shm_name || message_size == 0)
        return ln_set_error(NULL, LN_EINVAL,
                            "ln_ring_tap_open: a segment name and a message "
                            "size are required");
    const unsigned from_newest = mode & LN_TAP_INCLUDE_NEWEST;
    mode &= ~LN_TAP_INCLUDE_NEWEST;
    if (mode != LN_TAP_EVERY && mode != LN_TAP_NEWEST)
        return ln_set_error(NULL, LN_EINVAL,
                            "ln_ring_tap_open: mode %u is neither "
                            "LN_TAP_EVERY nor LN_TAP_NEWEST",
                            mode);
    ln_ring_tap* t = calloc(1, sizeof(*t));
    if (!t)
        return ln_set_error(NULL, LN_ENOMEM, "out of memory");
    int rc = ln_ring_attach(&t->ring, shm_name, layout_hash, message_size);
    if (rc != LN_OK) {
        free(t);
        return rc;
    }
    rc = ln_ring_follow(&t->ring);
    if (rc != LN_OK) {
        ln_ring_detach(&t->ring);
        free(t);
        return rc;
    }
    t->mode = mode;
    if (mode == LN_TAP_EVERY)
        ln_ring_count_tap(&t->ring, LN_RING_TAP_EVERY); /* no reader slot: keep the whole ring */
    t->cur.reader = -1;
    t->cur.whole_ring = mode == LN_TAP_EVERY;
    fit_cursor(t);
    uint64_t newest = atomic_load_explicit(&t->ring.hdr->write_seq, memory_order_acquire);
    t->cur.next = from_newest && newest > 0 ? newest : newest + 1;
    t->magic = LN_TAP_MAGIC;
    *out = t;
    return LN_OK;
}

void ln_ring_tap_close(ln_ring_tap* t)
{
    if (!t || t->magic != LN_TAP_MAGIC)
        return;
    if (t->injecting) /* closed between begin and commit: nothing is published */
        ln_ring_unlock(&t->ring);
    ln_ring_detach(&t->ring);
    t->magic = 0;
    free(t);
}

int ln_ring_tap_read(ln_ring_tap* t, void* buf, ln_sample_info* info, double timeout)
{
    int rc = bad_tap(t, "ln_ring_tap_read");
    if (rc != LN_OK)
        return rc;
    if (!buf)
        return ln_set_error(NULL, LN_EINVAL, "ln_ring_tap_read: buf is NULL");
    if (isnan(timeout))
        return ln_set_error(NULL, LN_EINVAL, "ln_ring_tap_read: timeout is NaN");
    if (t->borrowed)
        return ln_set_error(NULL, LN_EBUSY, "ln_ring_tap_read: a borrowed sample is not released");
    if (t->mode == LN_TAP_NEWEST) /* a reading tap: writers keep the newest for it */
        ln_ring_count_tap(&t->ring, LN_RING_TAP_NEWEST);
    uint64_t expected = t->cur.next;
    uint64_t word;
    int64_t ts;
    rc = ln_ring_read_copy(&t->ring, &t->cur, timeout, 0, buf, &word, &ts);
    if (rc == LN_EAGAIN || rc == LN_ETIMEOUT)
        return ln_set_error(NULL, LN_ETIMEOUT, "tap on '%s': no sample within %g s", t->ring.name,
                            timeout);
    if (rc != LN_OK)
        return rc;
    uint64_t seq = LN_SLOT_SEQ(word);
    if (info) {
        info->seq = seq;
        info->timestamp_ns = ts;
        /* Every number between the previous sample and this one, in both modes: samples
         * overwritten before the tap got to them, skipped for the newest, or never written
         * here (lost on the network). */
        info->overruns = seq - expected;
    }
    t->cur.pending = 0;
    return LN_OK;
}

int ln_ring_tap_borrow(ln_ring_tap* t, const void** payload, ln_sample_info* info, double timeout)
{
    int rc = bad_tap(t, "ln_ring_tap_borrow");
    if (rc != LN_OK)
        return rc;
    if (!payload)
        return ln_set_error(NULL, LN_EINVAL, "ln_ring_tap_borrow: payload is NULL");
    if (isnan(timeout))
        return ln_set_error(NULL, LN_EINVAL, "ln_ring_tap_borrow: timeout is NaN");
    if (t->borrowed)
        return ln_set_error(NULL, LN_EBUSY,
                            "ln_ring_tap_borrow: a borrowed sample is not released");
    if (t->mode == LN_TAP_NEWEST)
        ln_ring_count_tap(&t->ring, LN_RING_TAP_NEWEST);
    uint64_t expected = t->cur.next;
    ln_ring_slot* slot;
    uint64_t word;
    rc = ln_ring_next(&t->ring, &t->cur, timeout, 0, &slot, &word);
    if (rc == LN_EAGAIN || rc == LN_ETIMEOUT)
        return ln_set_error(NULL, LN_ETIMEOUT, "tap on '%s': no sample within %g s", t->ring.name,
                            timeout);
    if (rc != LN_OK)
        return rc;
    t->borrowed = slot;
    t->borrowed_word = word;
    *payload = ln_ring_payload(slot);
    if (info) {
        info->seq = LN_SLOT_SEQ(word);
        info->timestamp_ns = slot->timestamp_ns; /* checked with the payload at release */
        info->overruns = info->seq - expected;
    }
    t->cur.pending = 0;
    return LN_OK;
}

int ln_ring_tap_release(ln_ring_tap* t)
{
    int rc = bad_tap(t, "ln_ring_tap_release");
    if (rc != LN_OK)
        return rc;
    if (!t->borrowed)
        return ln_set_error(NULL, LN_EINVAL, "ln_ring_tap_release: nothing is borrowed");
    ln_ring_slot* slot = t->borrowed;
    t->borrowed = NULL;
    if (ln_ring_finish(&t->ring, &t->cur, slot, t->borrowed_word, 0) != LN_OK)
        return ln_set_error(NULL, LN_EOVERRUN,
                            "tap on '%s': sample %llu was overwritten while borrowed", t->ring.name,
                            (unsigned long long)LN_SLOT_SEQ(t->borrowed_word));
    return LN_OK;
}

/* Takes the write lock on the newest ring and begins sample seq there: LN_OK with *slot, the
 * lock held; otherwise the lock is not held. */
static int inject_start(ln_ring_tap* t, uint64_t seq, ln_ring_slot** slot)
{
    if (seq > LN_RING_MAX_SEQ)
        return ln_set_error(NULL, LN_EINVAL,
                            "ln_ring_tap_inject: sequence number %llu is beyond %llu",
                            (unsigned long long)seq, (unsigned long long)LN_RING_MAX_SEQ);
    ln_deadline d = ln_deadline_in(LN_TAP_LOCK_TIMEOUT);
    int rc;
    for (;;) {
        if ((rc = ln_ring_lock(&t->ring, &d)) != LN_OK)
            return rc;
        if (!atomic_load_explicit(&t->ring.hdr->retired, memory_order_acquire))
            break;
        /* Retired: its sequence numbers live on in the successor; write there. */
        ln_ring_unlock(&t->ring);
        if ((rc = ln_ring_follow(&t->ring)) != LN_OK)
            return rc;
        fit_cursor(t);
    }
    uint64_t newest = atomic_load_explicit(&t->ring.hdr->write_seq, memory_order_relaxed);
    if (seq <= newest) {
        ln_ring_unlock(&t->ring);
        return ln_set_error(NULL, LN_EOVERRUN,
                            "tap on '%s': sample %llu is not newer than "
                            "the ring's newest, %llu",
                            t->ring.name, (unsigned long long)seq, (unsigned long long)newest);
    }
    /* No waiting for queued readers: a slot they have not read yet is overwritten and they
     * count it as lost, as with any publisher that does not wait. */
    *slot = ln_ring_begin_seq(&t->ring, seq);
    return LN_OK;
}

int ln_ring_tap_inject_begin(ln_ring_tap* t, uint64_t seq, void** payload)
{
    int rc = bad_tap(t, "ln_ring_tap_inject_begin");
    if (rc != LN_OK)
        return rc;
    if (!payload)
        return ln_set_error(NULL, LN_EINVAL, "ln_ring_tap_inject_begin: payload is NULL");
    if (t->injecting)
        return ln_set_error(NULL, LN_EBUSY, "ln_ring_tap_inject_begin: a sample is begun");
    ln_ring_slot* slot = NULL;
    if ((rc = inject_start(t, seq, &slot)) != LN_OK)
        return rc;
    t->injecting = slot;
    t->injecting_seq = seq;
    *payload = ln_ring_payload(slot);
    return LN_OK;
}

int ln_ring_tap_inject_commit(ln_ring_tap* t, int64_t timestamp_ns)
{
    int rc = bad_tap(t, "ln_ring_tap_inject_commit");
    if (rc != LN_OK)
        return rc;
    if (!t->injecting)
        return ln_set_error(NULL, LN_EINVAL, "ln_ring_tap_inject_commit: nothing is begun");
    ln_ring_commit_seq(&t->ring, t->injecting, t->injecting_seq, timestamp_ns);
    t->injecting = NULL;
    return ln_ring_unlock(&t->ring);
}

int ln_ring_tap_inject_abort(ln_ring_tap* t)
{
    int rc = bad_tap(t, "ln_ring_tap_inject_abort");
    if (rc != LN_OK)
        return rc;
    if (!t->injecting)
        return ln_set_error(NULL, LN_EINVAL, "ln_ring_tap_inject_abort: nothing is begun");
    t->injecting = NULL; /* the slot stays WRITING: free for the next writer, never read */
    return ln_ring_unlock(&t->ring);
}

int ln_ring_tap_inject(ln_ring_tap* t, const void* data, uint64_t seq, int64_t timestamp_ns)
{
    int rc = bad_tap(t, "ln_ring_tap_inject");
    if (rc != LN_OK)
        return rc;
    if (!data)
        return ln_set_error(NULL, LN_EINVAL, "ln_ring_tap_inject: data is NULL");
    void* payload;
    if ((rc = ln_ring_tap_inject_begin(t, seq, &payload)) != LN_OK)
        return rc;
    memcpy(payload, data, t->ring.message_size);
    return ln_ring_tap_inject_commit(t, timestamp_ns);
}

uint64_t ln_ring_tap_write_seq(ln_ring_tap* t)
{
    if (bad_tap(t, "ln_ring_tap_write_seq") != LN_OK)
        return 0;
    const ln_ring_header* h = t->ring.hdr;
    if (!atomic_load_explicit(&h->retired, memory_order_acquire))
        return atomic_load_explicit(&h->write_seq, memory_order_acquire);
    /* A private walk along the successors: the tap itself moves on only when it reads past
     * the end of this ring or injects. */
    ln_ring peek;
    uint64_t seq = atomic_load_explicit(&h->write_seq, memory_order_acquire);
    if (ln_ring_attach(&peek, t->ring.name, t->ring.layout_hash, t->ring.message_size) != LN_OK)
        return seq;
    if (ln_ring_follow(&peek) == LN_OK)
        seq = atomic_load_explicit(&peek.hdr->write_seq, memory_order_acquire);
    ln_ring_detach(&peek);
    return seq;
}

uint32_t ln_ring_tap_slots(const ln_ring_tap* t)
{
    if (bad_tap(t, "ln_ring_tap_slots") != LN_OK)
        return 0;
    return t->ring.slot_count;
}

const char* ln_ring_tap_segment(const ln_ring_tap* t)
{
    if (bad_tap(t, "ln_ring_tap_segment") != LN_OK)
        return NULL;
    return t->ring.name;
}
