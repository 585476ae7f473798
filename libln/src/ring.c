/* ring.c — the lock-free reader and the serialized writer of a topic ring (see ring.h for the
 * memory-ordering protocol).  Everything here runs in the publishing or subscribing process;
 * the manager only creates, sizes and retires rings (ring_admin.c). */
#include "ring.h"
#include "bell.h"

#include <errno.h>
#include <sched.h>
#include <stdio.h>
#include <string.h>

#include "client_internal.h"
#include "futex.h"

uint64_t ln_ring_header_bytes(void)
{
    uint64_t page = 4096;
    return (sizeof(ln_ring_header) + page - 1) / page * page;
}

uint64_t ln_ring_stride(uint64_t message_size)
{
    if (message_size > UINT32_MAX)
        return 0; /* never a valid stride: rejected by create and attach */
    return (sizeof(ln_ring_slot) + message_size + 63) / 64 * 64;
}

int ln_ring_check_header(const ln_ring_header* h, uint64_t size, const char* name)
{
    const char* why = NULL;
    if (size < ln_ring_header_bytes())
        why = "too small for a ring header";
    else if (atomic_load_explicit((const _Atomic uint64_t*)&h->magic, memory_order_acquire) !=
             LN_RING_MAGIC)
        why = "no ring magic";
    else if (h->version != LN_RING_VERSION)
        return ln_set_error(NULL, LN_EVERSION,
                            "shared memory '%s' is a topic ring of format "
                            "version %u, this library uses %u",
                            name, h->version, LN_RING_VERSION);
    else if (h->header_size != ln_ring_header_bytes())
        why = "its header size differs from this library's";
    else if (h->segment_size != size)
        why = "its recorded size differs from the segment's";
    else if (h->slot_count < 2 || h->slot_count > LN_RING_MAX_SLOTS || h->message_size == 0 ||
             h->slot_stride == 0 || h->slot_stride != ln_ring_stride(h->message_size) ||
             h->header_size + (uint64_t)h->slot_count * h->slot_stride != size)
        why = "inconsistent ring geometry";
    if (why)
        return ln_set_error(NULL, LN_EPROTOCOL,
                            "shared memory '%s' is not a usable topic ring: "
                            "%s",
                            name, why);
    return LN_OK;
}

int ln_ring_attach(ln_ring* ring, const char* name, uint64_t layout_hash, uint64_t message_size)
{
    uint64_t size = 0;
    memset(ring, 0, sizeof(*ring));
    int rc = ln_shm_open(name, 0, &ring->map, &size);
    if (rc != LN_OK)
        return rc;
    ln_ring_header* h = ring->map.addr;
    if ((rc = ln_ring_check_header(h, size, name)) != LN_OK) {
        ln_shm_unmap(&ring->map);
        return rc;
    }
    if (h->layout_hash != layout_hash || h->message_size != message_size) {
        rc = ln_set_error(NULL, LN_ELAYOUT,
                          "topic '%.*s' in '%s' has md '%.*s' (hash 0x%016llx, %llu bytes), the "
                          "port expects hash 0x%016llx, %llu bytes",
                          LN_RING_NAME_MAX, h->topic, name, LN_RING_NAME_MAX, h->md_name,
                          (unsigned long long)h->layout_hash, (unsigned long long)h->message_size,
                          (unsigned long long)layout_hash, (unsigned long long)message_size);
        ln_shm_unmap(&ring->map);
        return rc;
    }
    ring->hdr = h;
    ring->slots = (uint8_t*)h + h->header_size;
    ring->slot_count = h->slot_count;
    ring->stride = h->slot_stride;
    ring->layout_hash = layout_hash;
    ring->message_size = message_size;
    snprintf(ring->name, sizeof(ring->name), "%s", name);
    return LN_OK;
}

void ln_ring_detach(ln_ring* ring)
{
    if (ring->tap_kind != LN_RING_TAP_NONE && ring->hdr)
        atomic_fetch_sub_explicit(ring->tap_kind == LN_RING_TAP_EVERY ? &ring->hdr->taps
                                                                      : &ring->hdr->newest_taps,
                                  1, memory_order_seq_cst);
    ring->tap_kind = LN_RING_TAP_NONE;
    ln_shm_unmap(&ring->map);
    ring->hdr = NULL;
    ring->slots = NULL;
}

#define LN_MAX_GENERATION_HOPS 64

int ln_ring_follow_once(ln_ring* ring)
{
    char next[LN_RING_NAME_MAX];
    memcpy(next, ring->hdr->successor, sizeof(next));
    next[sizeof(next) - 1] = '\0';
    if (!next[0] || strcmp(next, ring->name) == 0)
        return ln_set_error(NULL, LN_EPROTOCOL,
                            "topic '%.*s': ring '%s' is retired without a "
                            "valid successor",
                            LN_RING_NAME_MAX, ring->hdr->topic, ring->name);
    ln_ring fresh;
    int rc = ln_ring_attach(&fresh, next, ring->layout_hash, ring->message_size);
    if (rc != LN_OK)
        return rc;
    ln_ring_count_tap(&fresh, ring->tap_kind); /* counted there before no longer here */
    ln_ring_detach(ring);
    *ring = fresh;
    return LN_OK;
}

int ln_ring_follow(ln_ring* ring)
{
    for (int hop = 0; atomic_load_explicit(&ring->hdr->retired, memory_order_acquire); hop++) {
        if (hop == LN_MAX_GENERATION_HOPS)
            return ln_set_error(NULL, LN_EPROTOCOL,
                                "topic '%.*s': more than %d retired rings "
                                "in a row (a cycle?)",
                                LN_RING_NAME_MAX, ring->hdr->topic, LN_MAX_GENERATION_HOPS);
        int rc = ln_ring_follow_once(ring);
        if (rc != LN_OK)
            return rc;
    }
    return LN_OK;
}

void ln_ring_count_tap(ln_ring* ring, int kind)
{
    if (ring->tap_kind != LN_RING_TAP_NONE || kind == LN_RING_TAP_NONE)
        return;
    atomic_fetch_add_explicit(kind == LN_RING_TAP_EVERY ? &ring->hdr->taps
                                                        : &ring->hdr->newest_taps,
                              1, memory_order_seq_cst);
    ring->tap_kind = kind;
}

const struct timespec* ln_deadline_at(ln_deadline* d)
{
    if (!d->fixed) {
        clock_gettime(CLOCK_MONOTONIC, &d->at);
        double whole = (double)(long long)d->timeout;
        d->at.tv_sec += (time_t)whole;
        d->at.tv_nsec += (long)((d->timeout - whole) * 1e9);
        if (d->at.tv_nsec >= 1000000000L) {
            d->at.tv_sec += 1;
            d->at.tv_nsec -= 1000000000L;
        }
        d->fixed = 1;
    }
    return &d->at;
}

int ln_deadline_left(ln_deadline* d, struct timespec* rel)
{
    if (d->forever)
        return 0;
    const struct timespec* at = ln_deadline_at(d);
    struct timespec now;
    clock_gettime(CLOCK_MONOTONIC, &now);
    rel->tv_sec = at->tv_sec - now.tv_sec;
    rel->tv_nsec = at->tv_nsec - now.tv_nsec;
    if (rel->tv_nsec < 0) {
        rel->tv_sec -= 1;
        rel->tv_nsec += 1000000000L;
    }
    if (rel->tv_sec < 0 || (rel->tv_sec == 0 && rel->tv_nsec == 0))
        return ETIMEDOUT;
    return 0;
}

/* The previous owner died holding the lock: finish what it provably completed. */
static void recover(ln_ring* ring)
{
    ln_ring_header* h = ring->hdr;
    if (atomic_load_explicit(&h->retired, memory_order_acquire))
        return; /* its sequence numbers live on in the successor */
    uint64_t n = atomic_load_explicit(&h->write_seq, memory_order_relaxed) + 1;
    /* It may have died before pointing the directory at the slot: look at every slot. */
    for (uint32_t i = 0; i < ring->slot_count; i++) {
        ln_ring_slot* slot = ln_ring_slot_index(ring, i);
        if (atomic_load_explicit(&slot->seq, memory_order_acquire) ==
            LN_SLOT_WORD(n, LN_SLOT_COMMITTED)) {
            atomic_store_explicit(&h->slot_of[n % ring->slot_count], i, memory_order_release);
            atomic_store_explicit(&h->write_seq, n, memory_order_seq_cst);
            ln_ring_wake_readers(ring);
            break;
        }
    }
    /* A slot left WRITING is rewritten under the same number by the next writer. */
}

static inline void cpu_relax(void)
{
#if defined(__x86_64__) || defined(__i386__)
    __builtin_ia32_pause();
#elif defined(__aarch64__)
    __asm__ volatile("yield");
#endif
}

int ln_ring_lock(ln_ring* ring, ln_deadline* d)
{
    pthread_mutex_t* m = &ring->hdr->write_lock;
    int rc = pthread_mutex_trylock(m);
    /* Another publisher's write takes well under a microsecond: wait that out even when the
     * caller does not want to wait, before blocking or giving up. */
    for (int spin = 0; rc == EBUSY && spin < 2000; spin++) {
        cpu_relax();
        rc = pthread_mutex_trylock(m);
    }
    if (rc == EBUSY && (d->forever || d->timeout > 0))
        rc = d->forever ? pthread_mutex_lock(m)
                        : pthread_mutex_clocklock(m, CLOCK_MONOTONIC, ln_deadline_at(d));
    if (rc == 0)
        return LN_OK;
    if (rc == EOWNERDEAD) {
        if (ring->slots) /* the manager maps only the header; it never writes samples */
            recover(ring);
        pthread_mutex_consistent(m);
        return LN_OK;
    }
    if (rc == ETIMEDOUT || rc == EBUSY)
        return ln_set_error(NULL, LN_ETIMEOUT,
                            "topic '%.*s': another publisher holds the write side (a loan?)",
                            LN_RING_NAME_MAX, ring->hdr->topic);
    return ln_set_errno_error(NULL, rc, "topic '%.*s': write lock", LN_RING_NAME_MAX,
                              ring->hdr->topic);
}

int ln_ring_unlock(ln_ring* ring)
{
    int rc = pthread_mutex_unlock(&ring->hdr->write_lock);
    if (rc != 0)
        return ln_set_errno_error(NULL, rc, "topic '%.*s': releasing the write lock",
                                  LN_RING_NAME_MAX, ring->hdr->topic);
    return LN_OK;
}

/* Reader slot i: 1 with its buffers and next sequence number if a subscriber holds it. */
static int active_reader(const ln_ring_header* h, uint32_t i, uint32_t* buffers, uint64_t* next)
{
    const ln_ring_reader* r = &h->readers[i];
    if (!atomic_load_explicit(&r->active, memory_order_acquire))
        return 0;
    *buffers = atomic_load_explicit(&r->buffers, memory_order_relaxed);
    *next = atomic_load_explicit(&r->next_seq, memory_order_seq_cst);
    return 1;
}

/* 1 if some queued reader would lose its oldest unread sample when sample n is written. */
static int reader_full(const ln_ring_header* h, uint64_t n)
{
    uint32_t buffers;
    uint64_t next;
    for (uint32_t i = 0; i < LN_RING_MAX_READERS; i++)
        if (active_reader(h, i, &buffers, &next) && buffers > 1 && n >= next && n - next >= buffers)
            return 1;
    return 0;
}

int ln_ring_has_space(const ln_ring* ring)
{
    uint64_t n = atomic_load_explicit(&ring->hdr->write_seq, memory_order_relaxed) + 1;
    return !reader_full(ring->hdr, n);
}

int ln_ring_sleep_for_space(ln_ring* ring, ln_deadline* d)
{
    ln_ring_header* h = ring->hdr;
    uint32_t v = ln_futex_announce(&h->space_futex);
    uint64_t n = atomic_load_explicit(&h->write_seq, memory_order_seq_cst) + 1;
    if (!reader_full(h, n) || atomic_load_explicit(&h->retired, memory_order_acquire))
        return LN_OK;
    struct timespec rel;
    int err = ln_deadline_left(d, &rel);
    if (err == 0)
        err = ln_futex_wait(&h->space_futex, v, d->forever ? NULL : &rel);
    if (err == ETIMEDOUT)
        return ln_set_error(NULL, LN_ETIMEOUT,
                            "topic '%.*s': a queued subscriber has no free buffer",
                            LN_RING_NAME_MAX, h->topic);
    return LN_OK;
}

static int hot_ring(const ln_ring* ring) { return ring->message_size >= LN_RING_HOT_BYTES; }

/* Of a hot ring: the first sample number a reader may still want once sample n is written
 * (n > newest): the samples in [keep, newest] stay where they are (keep = newest + 1: none).
 * A queued reader wants what it has not read of its newest `buffers`; a latest reader the
 * newest unless it has read it, and the sample it is reading; a tap that reads every sample
 * everything the ring can hold, one that reads the newest the newest.  Reader positions
 * only grow, so a stale one keeps more. */
static uint64_t keep_from(const ln_ring* ring, uint64_t n, uint64_t newest)
{
    const ln_ring_header* h = ring->hdr;
    if (atomic_load_explicit(&h->taps, memory_order_seq_cst) > 0)
        return n > ring->slot_count ? n - ring->slot_count + 1 : 0;
    uint64_t keep = newest + 1;
    if (atomic_load_explicit(&h->newest_taps, memory_order_seq_cst) > 0)
        keep = newest;
    for (uint32_t i = 0; i < LN_RING_MAX_READERS; i++) {
        uint32_t buffers;
        uint64_t next, from;
        if (!active_reader(h, i, &buffers, &next))
            continue;
        if (buffers > 1) {
            from = n >= buffers ? n - buffers + 1 : 0;
            if (next > from)
                from = next;
        } else {
            from = next <= newest ? newest : newest + 1;
            uint64_t holding = atomic_load_explicit(&h->readers[i].holding, memory_order_seq_cst);
            if (holding && holding - 1 < from)
                from = holding - 1;
        }
        if (from < keep)
            keep = from;
    }
    return keep;
}

/* 1 if a slot whose seq word is `word` may take a new sample: it holds none (fresh: 0), an
 * unfinished one (WRITING: aborted, or its writer died), or one below `keep` or above `newest`
 * (committed by a writer that died before announcing it, and given up by recover). */
static int slot_free(uint64_t word, uint64_t keep, uint64_t newest)
{
    uint64_t s = LN_SLOT_SEQ(word);
    return s == 0 || LN_SLOT_STATE(word) != LN_SLOT_COMMITTED || s < keep || s > newest;
}

/* The slot the directory gives for sample s if that slot still holds s, else slot_count. */
static uint32_t slot_holding(const ln_ring* ring, uint64_t s)
{
    uint32_t i =
        atomic_load_explicit(&ring->hdr->slot_of[s % ring->slot_count], memory_order_relaxed);
    if (i < ring->slot_count &&
        atomic_load_explicit(&ln_ring_slot_index(ring, i)->seq, memory_order_relaxed) ==
            LN_SLOT_WORD(s, LN_SLOT_COMMITTED))
        return i;
    return ring->slot_count;
}

/* The slot for sample n (see ring.h).  Small samples: slot n mod slot_count, as the ring
 * always had it (their directory never moves).  Large ones: the newest's or the second
 * newest's slot when no reader wants its sample any more; else, the fast case of readers
 * that lag, the slot the directory gives for n's position if it still holds n - slot_count
 * or older, which no reader can want; else (after hot reuse moved samples around) the
 * oldest free slot. */
static uint32_t choose_slot(const ln_ring* ring, uint64_t n)
{
    const ln_ring_header* h = ring->hdr;
    const uint32_t count = ring->slot_count;
    if (!hot_ring(ring))
        return n % count;
    uint64_t newest = atomic_load_explicit(&h->write_seq, memory_order_relaxed);
    uint64_t keep = keep_from(ring, n, newest);
    for (uint64_t back = 0; back < 2 && back < newest; back++) {
        uint64_t s = newest - back;
        uint32_t hot = s < keep ? slot_holding(ring, s) : count;
        if (hot < count)
            return hot;
    }
    uint32_t at = atomic_load_explicit(&h->slot_of[n % count], memory_order_relaxed);
    if (at < count) {
        uint64_t word =
            atomic_load_explicit(&ln_ring_slot_index(ring, at)->seq, memory_order_relaxed);
        if (slot_free(word, n >= count ? n - count + 1 : 0, newest))
            return at;
    }
    /* The oldest free sample; if a latest reader holds on to an old one so long that none is
     * free, the oldest but the newest (that reader's release then says it was overwritten). */
    uint32_t best = n % count, any = n % count;
    uint64_t oldest = UINT64_MAX, oldest_any = UINT64_MAX;
    for (uint32_t i = 0; i < count; i++) {
        uint64_t word =
            atomic_load_explicit(&ln_ring_slot_index(ring, i)->seq, memory_order_relaxed);
        uint64_t s = LN_SLOT_STATE(word) == LN_SLOT_COMMITTED ? LN_SLOT_SEQ(word) : 0;
        if (slot_free(word, keep, newest) && s < oldest) {
            oldest = s;
            best = i;
        }
        if (s != newest && s < oldest_any) {
            oldest_any = s;
            any = i;
        }
    }
    return oldest != UINT64_MAX ? best : any;
}

ln_ring_slot* ln_ring_begin_seq(ln_ring* ring, uint64_t seq)
{
    ln_ring_slot* slot = ln_ring_slot_index(ring, choose_slot(ring, seq));
    atomic_store_explicit(&slot->seq, LN_SLOT_WORD(seq, LN_SLOT_WRITING), memory_order_relaxed);
    atomic_thread_fence(memory_order_release);
    return slot;
}

void ln_ring_commit_seq(ln_ring* ring, ln_ring_slot* slot, uint64_t seq, int64_t timestamp_ns)
{
    slot->timestamp_ns = timestamp_ns;
    atomic_store_explicit(&slot->seq, LN_SLOT_WORD(seq, LN_SLOT_COMMITTED), memory_order_release);
    /* Small samples never move, so their directory stays the identity it was created as
     * (and readers' copies of its cache lines stay valid). */
    if (hot_ring(ring))
        atomic_store_explicit(&ring->hdr->slot_of[seq % ring->slot_count],
                              (uint32_t)(((uint8_t*)slot - ring->slots) / ring->stride),
                              memory_order_release);
    atomic_store_explicit(&ring->hdr->write_seq, seq, memory_order_seq_cst);
    ln_ring_wake_readers(ring);
}

ln_ring_slot* ln_ring_begin(ln_ring* ring)
{
    uint64_t n = atomic_load_explicit(&ring->hdr->write_seq, memory_order_relaxed) + 1;
    return ln_ring_begin_seq(ring, n);
}

void ln_ring_commit(ln_ring* ring, ln_ring_slot* slot)
{
    uint64_t n = atomic_load_explicit(&ring->hdr->write_seq, memory_order_relaxed) + 1;
    struct timespec now;
    clock_gettime(CLOCK_REALTIME, &now);
    ln_ring_commit_seq(ring, slot, n, (int64_t)now.tv_sec * 1000000000LL + now.tv_nsec);
}

void ln_ring_wake_readers(ln_ring* ring)
{
    ln_futex_wake_sleepers(&ring->hdr->data_futex); /* no system call unless one sleeps */
    if (atomic_load_explicit(&ring->hdr->bell_readers, memory_order_seq_cst))
        ln_ring_ring_bells(ring->hdr, 0);
}

int ln_ring_pick(ln_ring* ring, ln_ring_cursor* c, ln_ring_slot** slot, uint64_t* word)
{
    ln_ring_header* h = ring->hdr;
    for (;;) {
        uint64_t w = atomic_load_explicit(&h->write_seq, memory_order_acquire);
        /* No publisher gets there; n + 1 below would wrap and this loop never end. */
        if (w > LN_RING_MAX_SEQ)
            return ln_set_error(NULL, LN_EPROTOCOL,
                                "ring '%s' is corrupted: its write_seq %llu "
                                "is beyond every sequence number",
                                ring->name, (unsigned long long)w);
        if (w < c->next)
            return LN_EAGAIN;
        uint64_t n = w;
        if (c->buffers > 1) {
            if (w - c->next >= c->buffers) { /* more unread than buffers: drop the oldest */
                c->pending += w - c->buffers + 1 - c->next;
                c->next = w - c->buffers + 1;
            }
            n = c->next;
        }
        ln_ring_slot* s = ln_ring_sample_slot(ring, n);
        if (!s)
            return ln_set_error(NULL, LN_EPROTOCOL,
                                "ring '%s' is corrupted: the slot directory entry of sample "
                                "%llu is out of range",
                                ring->name, (unsigned long long)n);
        uint64_t got = atomic_load_explicit(&s->seq, memory_order_acquire);
        if (got == LN_SLOT_WORD(n, LN_SLOT_COMMITTED)) {
            if (c->buffers == 1 && c->reader >= 0 && hot_ring(ring))
                atomic_store_explicit(&h->readers[c->reader].holding, n + 1, memory_order_seq_cst);
            *slot = s;
            *word = got;
            return LN_OK;
        }
        if (c->buffers == 1) {
            /* The newest sample is not in its slot.  Either the slot never held it in this
             * ring (a successor ring starts with the old ring's sequence number but no
             * samples), or a writer is replacing it already: normally with write_seq moved
             * on, but a forwarded sample whose number jumped by a multiple of slot_count
             * lands in this very slot, and its writer may die before publishing it.  Pick
             * again only if write_seq moved; otherwise wait for the next sample instead of
             * spinning on this one. */
            if (atomic_load_explicit(&h->write_seq, memory_order_acquire) != w)
                continue;
            c->next = n + 1;
            return LN_EAGAIN;
        }
        /* The slot moved on to a newer sample, or never had n (a gap in forwarded numbers,
         * or a sample aborted or given up by its writer): n is gone. */
        c->pending += 1;
        c->next = n + 1;
    }
}

void ln_ring_publish_cursor(ln_ring* ring, const ln_ring_cursor* c)
{
    if (c->reader < 0)
        return;
    ln_ring_header* h = ring->hdr;
    if (c->buffers <= 1) { /* only writers choosing a hot slot care where a latest reader is */
        if (hot_ring(ring)) {
            atomic_store_explicit(&h->readers[c->reader].next_seq, c->next, memory_order_seq_cst);
            atomic_store_explicit(&h->readers[c->reader].holding, 0, memory_order_release);
        }
        return;
    }
    atomic_store_explicit(&h->readers[c->reader].next_seq, c->next, memory_order_seq_cst);
    ln_futex_wake_sleepers(&h->space_futex);
}

int ln_ring_finish(ln_ring* ring, ln_ring_cursor* c, ln_ring_slot* slot, uint64_t word,
                   int count_loss)
{
    atomic_thread_fence(memory_order_acquire);
    uint64_t n = LN_SLOT_SEQ(word);
    if (atomic_load_explicit(&slot->seq, memory_order_relaxed) != word) {
        if (c->buffers > 1) {
            c->pending += count_loss ? 1 : 0;
            c->next = n + 1;
        } else if (c->reader >= 0 && hot_ring(ring)) {
            atomic_store_explicit(&ring->hdr->readers[c->reader].holding, 0, memory_order_release);
        }
        return LN_EOVERRUN;
    }
    c->next = n + 1;
    ln_ring_publish_cursor(ring, c);
    return LN_OK;
}

/* Poll `done(ring, arg)` (yielding the CPU) for up to spin_us; 1 once it holds. */
static int spin_until(const ln_ring* ring, uint64_t arg, uint32_t spin_us,
                      int (*done)(const ln_ring*, uint64_t))
{
    if (spin_us == 0)
        return 0;
    struct timespec start, now;
    clock_gettime(CLOCK_MONOTONIC, &start);
    int64_t limit = (int64_t)spin_us * 1000;
    for (;;) {
        for (int i = 0; i < 8; i++) {
            if (done(ring, arg))
                return 1;
            /* Yield, not just pause: the other side on this CPU gets to run right away. */
            sched_yield();
        }
        clock_gettime(CLOCK_MONOTONIC, &now);
        if ((now.tv_sec - start.tv_sec) * 1000000000LL + (now.tv_nsec - start.tv_nsec) >= limit)
            return 0;
    }
}

static int space_or_retired(const ln_ring* ring, uint64_t unused)
{
    (void)unused;
    const ln_ring_header* h = ring->hdr;
    return atomic_load_explicit(&h->retired, memory_order_acquire) ||
           !reader_full(h, atomic_load_explicit(&h->write_seq, memory_order_acquire) + 1);
}

int ln_ring_spin_space(const ln_ring* ring, uint32_t spin_us)
{
    return spin_until(ring, 0, spin_us, space_or_retired);
}

static int data_or_retired(const ln_ring* ring, uint64_t seq)
{
    const ln_ring_header* h = ring->hdr;
    return atomic_load_explicit(&h->write_seq, memory_order_acquire) >= seq ||
           atomic_load_explicit(&h->retired, memory_order_acquire);
}

int ln_ring_spin_data(const ln_ring* ring, uint64_t seq, uint32_t spin_us)
{
    return spin_until(ring, seq, spin_us, data_or_retired);
}

int ln_ring_wait_data(ln_ring* ring, uint64_t seq, ln_deadline* d, _Atomic uint32_t* interrupted,
                      int stop_on_signal)
{
    ln_ring_header* h = ring->hdr;
    struct timespec rel;
    int err = 0;
    uint32_t v = ln_futex_announce(&h->data_futex);
    /* after announcing: an interrupt set before it is seen here, one after it wakes us */
    if (interrupted && atomic_exchange_explicit(interrupted, 0, memory_order_seq_cst))
        return LN_EINTR;
    if (atomic_load_explicit(&h->write_seq, memory_order_seq_cst) < seq &&
        !atomic_load_explicit(&h->retired, memory_order_acquire) &&
        (err = ln_deadline_left(d, &rel)) == 0)
        err = ln_futex_wait(&h->data_futex, v, d->forever ? NULL : &rel);
    return err == ETIMEDOUT ? LN_ETIMEOUT : (err == EINTR && stop_on_signal) ? LN_EINTR : LN_OK;
}

/* After following to a successor: the cursor's progress and its bell, in the new ring. */
static void moved(ln_ring* ring, ln_ring_cursor* c)
{
    if (c->whole_ring)
        c->buffers = ring->slot_count;
    ln_ring_publish_cursor(ring, c);
    if (c->bell && c->reader >= 0)
        ln_ring_set_bell(ring->hdr, (uint32_t)c->reader, c->bell, c->bell_tag);
}

int ln_ring_has_data(ln_ring* ring, ln_ring_cursor* c)
{
    for (;;) {
        int retired = atomic_load_explicit(&ring->hdr->retired, memory_order_acquire);
        if (atomic_load_explicit(&ring->hdr->write_seq, memory_order_seq_cst) >= c->next)
            return 1;
        if (!retired)
            return 0;
        int rc = ln_ring_follow_once(ring);
        if (rc != LN_OK)
            return rc;
        moved(ring, c);
    }
}

int ln_ring_next(ln_ring* ring, ln_ring_cursor* c, double timeout, uint32_t spin_us,
                 ln_ring_slot** slot, uint64_t* word)
{
    ln_deadline d = ln_deadline_in(timeout);
    int spun = 0;
    for (;;) {
        /* Read `retired` first: a sample committed before the retirement is then seen by the
         * pick below. */
        int retired = atomic_load_explicit(&ring->hdr->retired, memory_order_acquire);
        int rc = ln_ring_pick(ring, c, slot, word);
        if (rc != LN_EAGAIN)
            return rc;
        if (retired) {
            if ((rc = ln_ring_follow_once(ring)) != LN_OK)
                return rc;
            moved(ring, c);
            continue;
        }
        if (timeout == 0)
            return LN_EAGAIN;
        if (!spun) {
            spun = 1;
            if (ln_ring_spin_data(ring, c->next, spin_us))
                continue;
        }
        rc = ln_ring_wait_data(ring, c->next, &d, &c->interrupted, c->interruptible);
        if (rc != LN_OK)
            return rc;
    }
}

int ln_ring_read_copy(ln_ring* ring, ln_ring_cursor* c, double timeout, uint32_t spin_us, void* buf,
                      uint64_t* word, int64_t* ts)
{
    for (;;) {
        ln_ring_slot* slot;
        int rc = ln_ring_next(ring, c, timeout, spin_us, &slot, word);
        if (rc != LN_OK)
            return rc;
        memcpy(buf, ln_ring_payload(slot), ring->message_size);
        *ts = slot->timestamp_ns;
        if (ln_ring_finish(ring, c, slot, *word, 1) == LN_OK)
            return LN_OK;
        /* overwritten while copied: counted, take the next one */
    }
}
