/* ring.h — layout of a topic's shared-memory ring and the reader/writer algorithms on it.
 *
 * One segment per topic and generation: a header, then slot_count slots of slot_stride bytes.
 * Every slot starts with a sequence word `seq = (n << 2) | state` (n: publish sequence number,
 * state: COMMITTED or WRITING) followed by the publish timestamp and the payload.  Sample n is
 * in slot `slot_of[n % slot_count]` of the header (the slot directory): a writer picks the
 * slot, so that large samples go to the slot written most recently that no reader needs any
 * more (still in the CPU's caches) instead of rotating through the whole ring.
 *
 * Memory-ordering protocol (a seqlock per slot, C11 atomics):
 *  writer (holding write_lock):  n = write_seq + 1 (a forwarding tap: any n > write_seq);
 *      slot = a slot holding no sample a reader may still need (ln_ring_begin_seq)
 *      store(slot.seq, n|WRITING, relaxed); fence(release)      -- readers see WRITING first
 *      copy payload, timestamp
 *      store(slot.seq, n|COMMITTED, release)                     -- payload before seq
 *      store(slot_of[n % slot_count], slot, release)   -- hot-slot sizes; smaller never move
 *      store(write_seq, n, seq_cst); if the sleepers bit of data_futex is set (seq_cst load):
 *      change data_futex, clear the bit, FUTEX_WAKE
 *  reader:  w = load(write_seq, acquire); pick n <= w; slot = load(slot_of[n % slot_count],
 *      acquire); s1 = load(slot.seq, acquire)
 *      s1 must be n|COMMITTED; copy payload; fence(acquire); s2 = load(slot.seq, relaxed)
 *      s1 != s2 means a writer reused the slot meanwhile: the copy is discarded (never torn).
 * A reader that finds slot_of pointing at a slot that holds another number has lost n (the
 * writer only reuses a slot once no reader can want its sample, see ln_ring_begin_seq).
 * Sequence numbers are gap-free on the publisher's host.  A ring fed by a forwarding tap
 * (samples from another host) has gaps where the network lost samples: a number below
 * write_seq whose slot does not hold it is simply not there; queued readers count it as lost,
 * latest readers never ask for it.
 *  sleeping reader: v = fetch_or(data_futex, SLEEPERS) (seq_cst); re-check write_seq
 *      (seq_cst); futex_wait(data_futex, v).  The seq_cst pairs (write_seq store, futex load)
 *      and (futex fetch_or, write_seq load) guarantee that either the writer sees the sleeper
 *      or the sleeper sees the new sample.
 * Publishers are serialized by a robust process-shared mutex; a publisher killed while
 * holding it is detected (EOWNERDEAD) by the next one: a slot it left WRITING is simply
 * written again under the same sequence number (readers never saw that number, since
 * write_seq was not advanced), one it had fully COMMITTED is published.  Readers never take
 * a lock, so no publisher can block or corrupt a reader.
 */
#ifndef LN_RING_H
#define LN_RING_H

#include <pthread.h>
#include <stdalign.h>
#include <stdatomic.h>
#include <stdint.h>
#include <time.h>

#include "ln/ln.h"
#include "ln_admin.h"
#include "shm.h"

#define LN_RING_MAGIC 0x31474e49524e4c00ull /* "\0LNRING1" little-endian */
#define LN_RING_VERSION 3u                  /* 3: waitset bells in the reader slots */
#define LN_RING_MAX_READERS 64u
#define LN_RING_MAX_SLOTS 1025u /* 1,024 buffers + the one being written */
#define LN_RING_NAME_MAX 256

enum { LN_SLOT_COMMITTED = 0, LN_SLOT_WRITING = 1 };
#define LN_SLOT_SEQ(word) ((word) >> 2)
#define LN_SLOT_STATE(word) ((unsigned)((word)&3u))
#define LN_SLOT_WORD(seq, state) (((seq) << 2) | (uint64_t)(state))
#define LN_RING_MAX_SEQ (UINT64_MAX >> 2) /* what fits beside the state bits */

typedef struct ln_ring_reader {
    _Atomic uint32_t active; /* 1 while a subscriber holds this slot */
    _Atomic int32_t pid;
    _Atomic uint32_t buffers;
    uint32_t reserved0;
    _Atomic uint64_t next_seq; /* next sequence number it will read (publishers that wait) */
    /* rings of hot-slot size (LN_RING_HOT_BYTES), latest readers: the sample it copies or
     * has borrowed + 1 (0: none), so writers leave that slot alone */
    _Atomic uint64_t holding;
    /* a subscriber attached to a waitset (bell.h): its bell, the tag it sends, and 1 while a
     * ring is unanswered */
    _Atomic uint64_t bell;
    _Atomic uint32_t bell_tag;
    _Atomic uint32_t bell_pending;
    uint8_t reserved[16];
} ln_ring_reader;

typedef struct ln_ring_header {
    /* immutable after creation */
    uint64_t magic;
    uint32_t version;
    uint32_t header_size;
    uint64_t layout_hash;
    uint64_t message_size;
    uint64_t segment_size;
    uint32_t slot_count;
    uint32_t slot_stride;
    char topic[LN_RING_NAME_MAX];
    char md_name[LN_RING_NAME_MAX];
    /* written by the manager */
    alignas(64) _Atomic uint32_t publishers;
    _Atomic uint32_t subscribers;
    _Atomic uint32_t retired; /* 1: publishers and readers move to `successor` */
    char successor[LN_RING_NAME_MAX];
    /* publishers */
    alignas(64) pthread_mutex_t write_lock;
    alignas(64) _Atomic uint64_t write_seq;   /* last committed sequence number, 0: none yet */
    alignas(64) _Atomic uint32_t data_futex;  /* readers sleep here (futex.h) */
    alignas(64) _Atomic uint32_t space_futex; /* publishers waiting for queued readers */
    /* taps, which hold no reader slot (ln_ring_count_tap): those reading every sample make
     * writers keep the ring's whole depth; those reading the newest, the newest */
    alignas(64) _Atomic uint32_t taps;
    _Atomic uint32_t newest_taps;
    /* reader slots whose subscriber waits in a waitset (bit i: readers[i].bell), bell.h */
    _Atomic uint64_t bell_readers;
    alignas(64) ln_ring_reader readers[LN_RING_MAX_READERS];
    /* the slot directory: slot_of[n % slot_count] is the slot of sample n (identity at
     * creation); written under write_lock, validated by every reader */
    alignas(64) _Atomic uint32_t slot_of[LN_RING_MAX_SLOTS];
} ln_ring_header;

typedef struct ln_ring_slot {
    _Atomic uint64_t seq;
    int64_t timestamp_ns;
    uint8_t reserved[48];
    /* payload follows, 64-byte aligned */
} ln_ring_slot;

/* Bytes of the header region (page aligned) and of one slot (header + payload, 64-aligned). */
uint64_t ln_ring_header_bytes(void);
uint64_t ln_ring_stride(uint64_t message_size);

/* A mapped ring as a port sees it.  The geometry is copied at attach and never re-read from
 * shared memory, so a corrupted header cannot send a client out of bounds. */
typedef struct ln_ring {
    ln_map map;
    ln_ring_header* hdr;
    uint8_t* slots;
    uint32_t slot_count;
    uint32_t stride;
    uint64_t layout_hash; /* what attach checked, again for successors */
    uint64_t message_size;
    int tap_kind; /* LN_RING_TAP_*: counted in the header (moves along to successors) */
    char name[LN_RING_NAME_MAX];
} ln_ring;

/* Samples of at least this many bytes go to the hottest free slot (see ln_ring_begin_seq);
 * smaller ones rotate through the ring, where a copy costs less than looking for one. */
#define LN_RING_HOT_BYTES (64u * 1024u)

/* LN_OK if h (the first bytes of segment `name` of `size` bytes, at least the header's if
 * size says so) is a ring of this library's format with consistent geometry; else
 * LN_EPROTOCOL (LN_EVERSION for another ring format version) with a text saying why. */
int ln_ring_check_header(const ln_ring_header* h, uint64_t size, const char* name);
/* Map segment `name` and check that it is a ring of this version for the expected layout. */
int ln_ring_attach(ln_ring* ring, const char* name, uint64_t layout_hash, uint64_t message_size);
void ln_ring_detach(ln_ring* ring);
/* The ring is retired: attach its successor (same layout checks) and detach it.  On failure
 * the ring stays as it was. */
int ln_ring_follow_once(ln_ring* ring);
/* Follow successors until the ring is not retired (publishers: they write only the newest). */
int ln_ring_follow(ln_ring* ring);
/* A tap reading samples (it holds no reader slot): count it in the ring's header, and in every
 * successor it follows to, until detached.  EVERY: writers keep the whole depth of samples
 * for it (`taps`); NEWEST: the newest sample (`newest_taps`). */
enum { LN_RING_TAP_NONE = 0, LN_RING_TAP_EVERY = 1, LN_RING_TAP_NEWEST = 2 };
void ln_ring_count_tap(ln_ring* ring, int kind);

static inline ln_ring_slot* ln_ring_slot_index(const ln_ring* ring, uint32_t index)
{
    return (ln_ring_slot*)(ring->slots + (uint64_t)index * ring->stride);
}

/* The slot that holds, or last held, sample seq; NULL if its directory entry is out of range
 * (a corrupted header). */
static inline ln_ring_slot* ln_ring_sample_slot(const ln_ring* ring, uint64_t seq)
{
    uint32_t index =
        atomic_load_explicit(&ring->hdr->slot_of[seq % ring->slot_count], memory_order_acquire);
    return index < ring->slot_count ? ln_ring_slot_index(ring, index) : NULL;
}

static inline void* ln_ring_payload(ln_ring_slot* slot)
{
    return (uint8_t*)slot + sizeof(ln_ring_slot);
}

/* A timeout in seconds (< 0: none) turned into a CLOCK_MONOTONIC deadline lazily, on the first
 * wait, so calls that never wait never read the clock. */
typedef struct ln_deadline {
    int forever;
    int fixed; /* `at` computed */
    double timeout;
    struct timespec at;
} ln_deadline;

static inline ln_deadline ln_deadline_in(double timeout)
{
    /* negative, infinite or beyond ~30 years: no deadline (NaN is refused by the API) */
    ln_deadline d = {.forever = timeout < 0 || timeout > 1e9, .fixed = 0, .timeout = timeout};
    return d;
}
/* The absolute deadline (fixing it now if needed). */
const struct timespec* ln_deadline_at(ln_deadline* d);
/* Time left until the deadline into *rel; 0 if some is left, ETIMEDOUT if it passed. */
int ln_deadline_left(ln_deadline* d, struct timespec* rel);

/* Writer side (callers: port.c).  lock takes write_lock (recovering from a dead owner); with
 * a zero timeout it still tries for a few microseconds, so a publisher does not drop a sample
 * just because another one is in the middle of a write. */
int ln_ring_lock(ln_ring* ring, ln_deadline* d);
int ln_ring_unlock(ln_ring* ring);
/* Under the lock: 1 if every queued reader has room for one more sample. */
int ln_ring_has_space(const ln_ring* ring);
/* Without the lock: poll (yielding the CPU) for up to spin_us until every queued reader has
 * room for one more sample or the ring is retired; 1 if that happened. */
int ln_ring_spin_space(const ln_ring* ring, uint32_t spin_us);
/* Without the lock: sleep until a queued reader frees a buffer (or the ring is retired, or
 * the deadline passes: LN_ETIMEOUT).  May return LN_OK spuriously; callers re-check. */
int ln_ring_sleep_for_space(ln_ring* ring, ln_deadline* d);
/* Under the lock: start sample write_seq+1 and return its slot (marked WRITING): a slot
 * whose sample no reader can want any more (queued readers: within their buffers and not
 * read yet; latest readers: the newest unless they have read it, and what they hold; taps:
 * the whole ring or the newest).  Of those, samples of LN_RING_HOT_BYTES and more take the
 * newest sample's slot, else the second newest's (still in cache) when free; otherwise the
 * one holding the oldest.  Latest readers of such rings publish next_seq and `holding`. */
ln_ring_slot* ln_ring_begin(ln_ring* ring);
/* Under the lock: publish the slot begun last with the current time, then wake sleeping
 * readers. */
void ln_ring_commit(ln_ring* ring, ln_ring_slot* slot);
/* The same for a sample with a given number seq > write_seq (numbers may be skipped) and a
 * given timestamp: a forwarded sample keeps those of the publisher's host.  Commit points the
 * slot directory at the slot (hot-slot sizes) before it announces the sample. */
ln_ring_slot* ln_ring_begin_seq(ln_ring* ring, uint64_t seq);
void ln_ring_commit_seq(ln_ring* ring, ln_ring_slot* slot, uint64_t seq, int64_t timestamp_ns);
void ln_ring_wake_readers(ln_ring* ring);

/* Reader side.  A cursor is one subscriber's position: `next` is the next sequence number it
 * wants, `buffers` 1 for latest mode, N for queued mode (reader slot `reader` publishes
 * `next` for publishers that wait). */
typedef struct ln_ring_cursor {
    uint64_t next;
    uint32_t buffers;
    int reader;       /* reader slot index, -1 if none */
    uint64_t pending; /* overruns not yet reported by a read */
    uint64_t total;   /* overruns since subscribing */
    int whole_ring;   /* buffers follow the ring's slot count across growth (a tap, EVERY) */
    /* a subscriber in a waitset: its bell, registered again in every ring it follows to */
    uint64_t bell;
    uint32_t bell_tag;
    int interruptible;            /* a signal ends a blocking wait with LN_EINTR */
    _Atomic uint32_t interrupted; /* ln_inport_interrupt: the next wait returns LN_EINTR */
} ln_ring_cursor;

/* Choose the sample to read now: LN_OK with *slot and *word (its seq word) set, LN_EAGAIN if
 * there is none, LN_EPROTOCOL for a corrupted write_seq.  Samples a queued cursor can no
 * longer get are counted in `pending`. */
int ln_ring_pick(ln_ring* ring, ln_ring_cursor* c, ln_ring_slot** slot, uint64_t* word);
/* After the payload was copied or used: LN_OK if the slot still holds that sample (the cursor
 * moves on), LN_EOVERRUN if a publisher reused the slot meanwhile (pick again).  count_loss: a
 * queued cursor counts the sample as lost (0 when it was already handed out, as a borrow). */
int ln_ring_finish(ln_ring* ring, ln_ring_cursor* c, ln_ring_slot* slot, uint64_t word,
                   int count_loss);
/* Publish a queued cursor's position in its reader slot of `ring` (for waiting publishers). */
void ln_ring_publish_cursor(ln_ring* ring, const ln_ring_cursor* c);
/* Poll (yielding the CPU) for up to spin_us until a sample >= seq is committed or the ring is
 * retired; 1 if that happened. */
int ln_ring_spin_data(const ln_ring* ring, uint64_t seq, uint32_t spin_us);
/* Sleep until a sample >= seq is committed, the ring is retired, or the deadline passes
 * (LN_ETIMEOUT).  May return LN_OK spuriously; callers pick again.  LN_EINTR: *interrupted
 * (may be NULL) was set, which it clears, or a signal handler ran and stop_on_signal. */
int ln_ring_wait_data(ln_ring* ring, uint64_t seq, ln_deadline* d, _Atomic uint32_t* interrupted,
                      int stop_on_signal);

/* The read loop of every reader (subscriber ports and taps): find the next sample for cursor
 * c, waiting up to timeout (< 0 forever) after spinning up to spin_us once.  A retired ring
 * is left only once nothing more can come from it, one generation at a time, so queued
 * readers lose nothing across ring growth.  LN_OK with *slot and *word set, LN_EAGAIN if
 * timeout is 0 and there is none, LN_ETIMEOUT (no error text set: the caller words it), or
 * the error of a corrupted or vanished ring. */
int ln_ring_next(ln_ring* ring, ln_ring_cursor* c, double timeout, uint32_t spin_us,
                 ln_ring_slot** slot, uint64_t* word);
/* 1 if a read by cursor c would find a sample now (a retired ring is followed, as a read
 * would, once nothing more can come from it), 0 if not, or the error of following. */
int ln_ring_has_data(ln_ring* ring, ln_ring_cursor* c);
/* ln_ring_next, then copy the payload (message_size bytes) to buf and finish; a sample
 * overwritten while copied is counted and the next one taken.  On LN_OK *word and *ts hold
 * the sample's seq word and timestamp. */
int ln_ring_read_copy(ln_ring* ring, ln_ring_cursor* c, double timeout, uint32_t spin_us, void* buf,
                      uint64_t* word, int64_t* ts);

#endif /* LN_RING_H */
