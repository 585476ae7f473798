/* test_ring_tap.c — ring taps and ln_ring_admin_open without a manager: injected samples keep
 * their numbers and timestamps, gaps in the numbers (every reader kind counts them and goes
 * on), stale injects, borrowing in place and filling in place (also by a writer killed
 * meanwhile), both read modes, timeouts and wake-ups, following successor rings, and
 * re-adopting segments.  Links the static libln to compare with the internal reader. */
#include <fcntl.h>
#include <math.h>
#include <pthread.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/wait.h>
#include <unistd.h>

#include "futex.h"
#include "ln_test.h"
#include "ring.h"

#define MSG 96
#define HASH 0x5eedULL

static char seg_name[64];

static ln_ring_admin* make(const char* suffix, uint32_t slots)
{
    snprintf(seg_name, sizeof(seg_name), "/ln.taptest%d.%s", (int)getpid(), suffix);
    ln_ring_admin_unlink(seg_name);
    ln_ring_admin* a = NULL;
    LN_CHECK_EQ(ln_ring_admin_create(&a, seg_name, "tap.topic", "test/tap", HASH, MSG, slots),
                LN_OK);
    return a;
}

static void drop(ln_ring_admin* a, const char* name)
{
    ln_ring_admin_close(a);
    LN_CHECK_EQ(ln_ring_admin_unlink(name), LN_OK);
}

static ln_ring_tap* tap(const char* name, unsigned mode)
{
    ln_ring_tap* t = NULL;
    LN_CHECK_EQ(ln_ring_tap_open(&t, name, HASH, MSG, mode), LN_OK);
    return t;
}

/* A sample whose every byte is its sequence number's low byte: a torn or wrong copy shows. */
static int inject(ln_ring_tap* t, uint64_t seq)
{
    uint8_t data[MSG];
    memset(data, (int)(seq & 0xff), sizeof(data));
    return ln_ring_tap_inject(t, data, seq, (int64_t)seq * 1000 + 7);
}

/* One tap read with `timeout`; checks the payload and timestamp inject() gave it.  Returns the
 * sequence number, 0 on an error (its code in *rc if rc is not NULL). */
static uint64_t tap_read(ln_ring_tap* t, double timeout, uint64_t* overruns, int* rc)
{
    uint8_t buf[MSG];
    ln_sample_info info = {0};
    int r = ln_ring_tap_read(t, buf, &info, timeout);
    if (rc)
        *rc = r;
    if (r != LN_OK)
        return 0;
    for (int i = 0; i < MSG; i++)
        LN_CHECK_EQ(buf[i], info.seq & 0xff);
    LN_CHECK_EQ(info.timestamp_ns, (int64_t)info.seq * 1000 + 7);
    if (overruns)
        *overruns = info.overruns;
    return info.seq;
}

/* A subscriber's read through the ring's own reader (what ln_read does). */
static uint64_t port_read(ln_ring* r, ln_ring_cursor* c, int64_t* ts)
{
    uint8_t buf[MSG];
    for (;;) {
        ln_ring_slot* s;
        uint64_t word;
        if (ln_ring_pick(r, c, &s, &word) != LN_OK)
            return 0;
        memcpy(buf, ln_ring_payload(s), MSG);
        int64_t stamp = s->timestamp_ns;
        if (ln_ring_finish(r, c, s, word, 1) == LN_OK) {
            for (int i = 0; i < MSG; i++)
                LN_CHECK_EQ(buf[i], LN_SLOT_SEQ(word) & 0xff);
            if (ts)
                *ts = stamp;
            return LN_SLOT_SEQ(word);
        }
    }
}

static void test_inject_keeps_seq_and_timestamp(void)
{
    ln_ring_admin* a = make("keep", 8);
    LN_CHECK_EQ(ln_ring_admin_reserve_reader(a, 2, getpid(), 4), LN_OK);
    ln_ring_tap* in = tap(seg_name, LN_TAP_EVERY);
    ln_ring_tap* out = tap(seg_name, LN_TAP_EVERY);
    ln_ring r;
    LN_CHECK_EQ(ln_ring_attach(&r, seg_name, HASH, MSG), LN_OK);
    ln_ring_cursor latest = {.next = 1, .buffers = 1, .reader = -1};
    ln_ring_cursor queued = {.next = r.hdr->readers[2].next_seq, .buffers = 4, .reader = 2};
    LN_CHECK_EQ(ln_ring_tap_write_seq(in), 0);
    LN_CHECK_EQ(ln_ring_tap_slots(in), r.slot_count); // what a lagging sender measures by
    LN_CHECK(r.slot_count >= 8);

    uint8_t data[MSG];
    memset(data, 41, sizeof(data));
    LN_CHECK_EQ(ln_ring_tap_inject(in, data, 41, 1700000000123456789LL), LN_OK);
    LN_CHECK_EQ(ln_ring_tap_write_seq(in), 41);
    LN_CHECK_EQ(ln_ring_tap_write_seq(out), 41);
    uint64_t seq = 0;
    LN_CHECK_EQ(ln_ring_admin_write_seq(a, &seq), LN_OK);
    LN_CHECK_EQ(seq, 41);
    uint8_t buf[MSG];
    ln_sample_info info = {0};
    LN_CHECK_EQ(ln_ring_tap_read(out, buf, &info, 0), LN_OK);
    LN_CHECK_EQ(info.seq, 41);
    LN_CHECK_EQ(info.timestamp_ns, 1700000000123456789LL);
    LN_CHECK_EQ(info.overruns, 40); /* 1..40 never reached this ring */
    LN_CHECK_EQ(memcmp(buf, data, MSG), 0);

    int64_t ts = 0;
    LN_CHECK_EQ(port_read(&r, &latest, &ts), 41);
    LN_CHECK_EQ(ts, 1700000000123456789LL);
    LN_CHECK_EQ(port_read(&r, &queued, &ts), 41);
    LN_CHECK_EQ(ts, 1700000000123456789LL);
    LN_CHECK_EQ(queued.pending, 40);
    LN_CHECK_EQ(r.hdr->readers[2].next_seq, 42);

    /* A local publisher goes on from the injected number. */
    ln_deadline d = ln_deadline_in(-1);
    LN_CHECK_EQ(ln_ring_lock(&r, &d), LN_OK);
    ln_ring_slot* s = ln_ring_begin(&r);
    memset(ln_ring_payload(s), 42, MSG);
    ln_ring_commit(&r, s);
    ln_ring_unlock(&r);
    LN_CHECK_EQ(port_read(&r, &latest, NULL), 42);
    LN_CHECK_EQ(ln_ring_tap_read(out, buf, &info, 0), LN_OK);
    LN_CHECK_EQ(info.seq, 42);
    LN_CHECK_EQ(info.overruns, 0);
    LN_CHECK_EQ(buf[0], 42);
    ln_ring_detach(&r);
    ln_ring_tap_close(in);
    ln_ring_tap_close(out);
    drop(a, seg_name);
}

static void test_gaps_are_counted_and_skipped(void)
{
    ln_ring_admin* a = make("gaps", 16);
    LN_CHECK_EQ(ln_ring_admin_reserve_reader(a, 0, getpid(), 10), LN_OK);
    ln_ring_tap* in = tap(seg_name, LN_TAP_NEWEST);
    ln_ring_tap* every = tap(seg_name, LN_TAP_EVERY);
    ln_ring r;
    LN_CHECK_EQ(ln_ring_attach(&r, seg_name, HASH, MSG), LN_OK);
    ln_ring_cursor latest = {.next = 1, .buffers = 1, .reader = -1};
    ln_ring_cursor queued = {.next = 1, .buffers = 10, .reader = 0};
    LN_CHECK_EQ(inject(in, 1), LN_OK);
    LN_CHECK_EQ(inject(in, 2), LN_OK);
    LN_CHECK_EQ(inject(in, 5), LN_OK);
    uint64_t ov = 99;
    LN_CHECK_EQ(tap_read(every, 0, &ov, NULL), 1);
    LN_CHECK_EQ(ov, 0);
    LN_CHECK_EQ(tap_read(every, 0, &ov, NULL), 2);
    LN_CHECK_EQ(ov, 0);
    LN_CHECK_EQ(tap_read(every, 0, &ov, NULL), 5);
    LN_CHECK_EQ(ov, 2);
    int rc = 0;
    LN_CHECK_EQ(tap_read(every, 0, NULL, &rc), 0);
    LN_CHECK_EQ(rc, LN_ETIMEOUT);

    LN_CHECK_EQ(port_read(&r, &queued, NULL), 1);
    LN_CHECK_EQ(port_read(&r, &queued, NULL), 2);
    LN_CHECK_EQ(queued.pending, 0);
    LN_CHECK_EQ(port_read(&r, &queued, NULL), 5);
    LN_CHECK_EQ(queued.pending, 2); /* 3 and 4 */
    LN_CHECK_EQ(port_read(&r, &queued, NULL), 0);
    LN_CHECK_EQ(r.hdr->readers[0].next_seq, 6);
    LN_CHECK_EQ(port_read(&r, &latest, NULL), 5);
    LN_CHECK_EQ(port_read(&r, &latest, NULL), 0);

    /* A jump by the slot count lands in the newest sample's own slot. */
    LN_CHECK_EQ(inject(in, 5 + 16), LN_OK);
    LN_CHECK_EQ(tap_read(every, 0, &ov, NULL), 21);
    LN_CHECK_EQ(ov, 15);
    LN_CHECK_EQ(port_read(&r, &latest, NULL), 21);
    queued.pending = 0;
    LN_CHECK_EQ(port_read(&r, &queued, NULL), 21);
    LN_CHECK_EQ(queued.pending, 15);
    /* A jump far beyond the ring: queued readers skip to what the ring can hold at once. */
    LN_CHECK_EQ(inject(in, 1000000), LN_OK);
    queued.pending = 0;
    LN_CHECK_EQ(port_read(&r, &queued, NULL), 1000000);
    LN_CHECK_EQ(queued.pending, 1000000 - 22);
    LN_CHECK_EQ(tap_read(every, 0, &ov, NULL), 1000000);
    LN_CHECK_EQ(ov, 1000000 - 22);
    ln_ring_detach(&r);
    ln_ring_tap_close(in);
    ln_ring_tap_close(every);
    drop(a, seg_name);
}

/* Child: a latest and a queued reader must give up on a newest sample whose slot a writer is
 * still (or forever) filling with a later number, instead of spinning.  Exit 0 if so; the
 * alarm ends a child that spins. */
static void reader_child(const char* name, uint64_t newest) __attribute__((noreturn));
static void reader_child(const char* name, uint64_t newest)
{
    alarm(60);
    ln_ring r;
    if (ln_ring_attach(&r, name, HASH, MSG) != LN_OK)
        _exit(2);
    ln_ring_cursor latest = {.next = 1, .buffers = 1, .reader = -1};
    ln_ring_cursor queued = {.next = newest, .buffers = 4, .reader = -1};
    uint64_t got = port_read(&r, &latest, NULL) + port_read(&r, &queued, NULL);
    ln_deadline d = ln_deadline_in(0);
    int waited = ln_ring_wait_data(&r, latest.next, &d, NULL, 0);
    _exit(got == 0 && latest.next == newest + 1 && queued.pending == 1 && waited == LN_ETIMEOUT
              ? 0
              : 3);
}

static void test_writer_dead_in_newest_slot_does_not_hang_readers(void)
{
    ln_ring_admin* a = make("deadjump", 4);
    ln_ring_tap* in = tap(seg_name, LN_TAP_NEWEST);
    LN_CHECK_EQ(inject(in, 3), LN_OK);
    /* A forwarding writer that began sample 3 + 4 (the slot of 3) and never finished. */
    ln_ring w;
    LN_CHECK_EQ(ln_ring_attach(&w, seg_name, HASH, MSG), LN_OK);
    ln_deadline d = ln_deadline_in(-1);
    LN_CHECK_EQ(ln_ring_lock(&w, &d), LN_OK);
    ln_ring_begin_seq(&w, 7);
    ln_ring_unlock(&w);
    pid_t pid = fork();
    if (pid == 0)
        reader_child(seg_name, 3);
    int status = 0;
    waitpid(pid, &status, 0);
    LN_CHECK(WIFEXITED(status) && WEXITSTATUS(status) == 0);
    /* The next writer simply goes on. */
    LN_CHECK_EQ(inject(in, 8), LN_OK);
    ln_ring_cursor latest = {.next = 1, .buffers = 1, .reader = -1};
    LN_CHECK_EQ(port_read(&w, &latest, NULL), 8);
    ln_ring_detach(&w);
    ln_ring_tap_close(in);
    drop(a, seg_name);
}

static void test_stale_inject_changes_nothing(void)
{
    ln_ring_admin* a = make("stale", 4);
    ln_ring_tap* in = tap(seg_name, LN_TAP_EVERY);
    ln_ring r;
    LN_CHECK_EQ(ln_ring_attach(&r, seg_name, HASH, MSG), LN_OK);
    for (uint64_t i = 3; i <= 6; i++)
        LN_CHECK_EQ(inject(in, i), LN_OK);
    size_t bytes = (size_t)r.slot_count * r.stride;
    uint8_t* before = malloc(bytes);
    memcpy(before, r.slots, bytes);
    uint32_t futex = atomic_load(&r.hdr->data_futex);
    LN_CHECK_EQ(inject(in, 6), LN_EOVERRUN);
    LN_CHECK(strstr(ln_last_error(), "not newer") != NULL);
    LN_CHECK_EQ(inject(in, 4), LN_EOVERRUN);
    LN_CHECK_EQ(inject(in, 2), LN_EOVERRUN);
    LN_CHECK_EQ(inject(in, 0), LN_EOVERRUN);
    LN_CHECK_EQ(ln_ring_tap_inject(in, before, LN_RING_MAX_SEQ + 1, 0), LN_EINVAL);
    LN_CHECK_EQ(ln_ring_tap_inject(in, NULL, 9, 0), LN_EINVAL);
    LN_CHECK_EQ(memcmp(before, r.slots, bytes), 0);
    LN_CHECK_EQ(atomic_load(&r.hdr->write_seq), 6);
    LN_CHECK_EQ(atomic_load(&r.hdr->data_futex), futex);
    /* The lock was given back each time. */
    LN_CHECK_EQ(inject(in, 7), LN_OK);
    free(before);
    ln_ring_detach(&r);
    ln_ring_tap_close(in);
    drop(a, seg_name);
}

/* Borrowing leaves the sample in the ring: release says LN_OK while it stayed intact and
 * LN_EOVERRUN once a writer reused its slot meanwhile; one borrow at a time. */
static void test_borrow_and_release(void)
{
    ln_ring_admin* a = make("borrow", 2);
    ln_ring_tap* in = tap(seg_name, LN_TAP_NEWEST);
    ln_ring_tap* out = tap(seg_name, LN_TAP_EVERY);
    LN_CHECK_EQ(inject(in, 1), LN_OK);
    const void* p = NULL;
    ln_sample_info info;
    LN_CHECK_EQ(ln_ring_tap_borrow(out, &p, &info, 0), LN_OK);
    LN_CHECK_EQ(info.seq, 1);
    LN_CHECK_EQ(info.timestamp_ns, 1007);
    LN_CHECK_EQ(((const uint8_t*)p)[0], 1);
    LN_CHECK_EQ(((const uint8_t*)p)[MSG - 1], 1);
    uint8_t buf[MSG];
    LN_CHECK_EQ(ln_ring_tap_borrow(out, &p, &info, 0), LN_EBUSY);
    LN_CHECK_EQ(ln_ring_tap_read(out, buf, &info, 0), LN_EBUSY);
    LN_CHECK_EQ(ln_ring_tap_release(out), LN_OK);
    LN_CHECK_EQ(ln_ring_tap_release(out), LN_EINVAL);
    /* Sample 2 borrowed; the writer goes round the two slots and reuses its slot. */
    LN_CHECK_EQ(inject(in, 2), LN_OK);
    LN_CHECK_EQ(ln_ring_tap_borrow(out, &p, &info, 0), LN_OK);
    LN_CHECK_EQ(info.seq, 2);
    LN_CHECK_EQ(inject(in, 3), LN_OK);
    LN_CHECK_EQ(inject(in, 4), LN_OK);
    LN_CHECK_EQ(((const uint8_t*)p)[0], 4); /* what a sender would have sent: torn */
    LN_CHECK_EQ(ln_ring_tap_release(out), LN_EOVERRUN);
    LN_CHECK(strstr(ln_last_error(), "overwritten while borrowed") != NULL);
    /* The tap is past sample 2 and goes on with what the ring still holds: 3 and 4. */
    LN_CHECK_EQ(ln_ring_tap_borrow(out, &p, &info, 0), LN_OK);
    LN_CHECK_EQ(info.seq, 3);
    LN_CHECK_EQ(((const uint8_t*)p)[0], 3);
    LN_CHECK_EQ(ln_ring_tap_release(out), LN_OK);
    LN_CHECK_EQ(ln_ring_tap_borrow(out, &p, &info, 0), LN_OK);
    LN_CHECK_EQ(info.seq, 4);
    LN_CHECK_EQ(info.overruns, 0);
    LN_CHECK_EQ(ln_ring_tap_release(out), LN_OK);
    LN_CHECK_EQ(ln_ring_tap_borrow(out, &p, &info, 0), LN_ETIMEOUT);
    ln_ring_tap_close(out);
    ln_ring_tap_close(in);
    drop(a, seg_name);
}

/* Child: begins sample 5 in place, fills half of it and dies by SIGKILL holding the lock. */
static void die_while_injecting(const char* name) __attribute__((noreturn));
static void die_while_injecting(const char* name)
{
    ln_ring_tap* t = NULL;
    void* p = NULL;
    if (ln_ring_tap_open(&t, name, HASH, MSG, LN_TAP_NEWEST) != LN_OK ||
        ln_ring_tap_inject_begin(t, 5, &p) != LN_OK)
        _exit(2);
    memset(p, 0x55, MSG / 2);
    kill(getpid(), SIGKILL);
    _exit(3);
}

/* In-place injects: commit publishes under the given number and timestamp, abort leaves
 * nothing visible, the checks of inject apply, and a writer killed between begin and commit
 * leaves no sample and no held lock behind. */
static void test_inject_in_place(void)
{
    ln_ring_admin* a = make("inplace", 4);
    ln_ring_tap* in = tap(seg_name, LN_TAP_NEWEST);
    ln_ring_tap* out = tap(seg_name, LN_TAP_EVERY);
    void* p = NULL;
    LN_CHECK_EQ(ln_ring_tap_inject_begin(in, 2, &p), LN_OK);
    memset(p, 2, MSG);
    LN_CHECK_EQ(ln_ring_tap_inject_begin(in, 3, &p), LN_EBUSY);
    LN_CHECK_EQ(inject(in, 3), LN_EBUSY);
    LN_CHECK_EQ(ln_ring_tap_inject_commit(in, 2007), LN_OK);
    LN_CHECK_EQ(ln_ring_tap_inject_commit(in, 2007), LN_EINVAL);
    uint64_t overruns = 0;
    LN_CHECK_EQ(tap_read(out, 0, &overruns, NULL), 2);
    /* Aborted: never seen, and the number may still come. */
    LN_CHECK_EQ(ln_ring_tap_inject_begin(in, 3, &p), LN_OK);
    memset(p, 0xee, MSG);
    LN_CHECK_EQ(ln_ring_tap_inject_abort(in), LN_OK);
    LN_CHECK_EQ(ln_ring_tap_inject_abort(in), LN_EINVAL);
    int rc = LN_OK;
    LN_CHECK_EQ(tap_read(out, 0, NULL, &rc), 0);
    LN_CHECK_EQ(rc, LN_ETIMEOUT);
    LN_CHECK_EQ(ln_ring_tap_inject_begin(in, 2, &p), LN_EOVERRUN); /* not newer */
    LN_CHECK_EQ(ln_ring_tap_inject_begin(in, LN_RING_MAX_SEQ + 1, &p), LN_EINVAL);
    LN_CHECK_EQ(ln_ring_tap_inject_begin(in, 4, NULL), LN_EINVAL);
    /* Killed while filling sample 5: readers never see it, the next writer goes on. */
    pid_t pid = fork();
    if (pid == 0)
        die_while_injecting(seg_name);
    int status = 0;
    waitpid(pid, &status, 0);
    LN_CHECK(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL);
    LN_CHECK_EQ(tap_read(out, 0, NULL, &rc), 0);
    LN_CHECK_EQ(rc, LN_ETIMEOUT);
    LN_CHECK_EQ(inject(in, 6), LN_OK);
    LN_CHECK_EQ(tap_read(out, 0, &overruns, NULL), 6);
    LN_CHECK_EQ(overruns, 3); /* 3, 4 and 5 never came */
    /* Closed between begin and commit: the lock is given back. */
    LN_CHECK_EQ(ln_ring_tap_inject_begin(in, 7, &p), LN_OK);
    ln_ring_tap_close(in);
    in = tap(seg_name, LN_TAP_NEWEST);
    LN_CHECK_EQ(inject(in, 8), LN_OK);
    LN_CHECK_EQ(tap_read(out, 0, &overruns, NULL), 8);
    ln_ring_tap_close(out);
    ln_ring_tap_close(in);
    drop(a, seg_name);
}

static void test_modes_and_start_point(void)
{
    ln_ring_admin* a = make("modes", 4);
    ln_ring_tap* in = tap(seg_name, LN_TAP_EVERY);
    for (uint64_t i = 1; i <= 3; i++)
        LN_CHECK_EQ(inject(in, i), LN_OK);
    /* Fresh taps start after the newest sample present when they open. */
    ln_ring_tap* every = tap(seg_name, LN_TAP_EVERY);
    ln_ring_tap* newest = tap(seg_name, LN_TAP_NEWEST);
    int rc = 0;
    LN_CHECK_EQ(tap_read(every, 0, NULL, &rc), 0);
    LN_CHECK_EQ(rc, LN_ETIMEOUT);
    LN_CHECK_EQ(tap_read(newest, 0, NULL, &rc), 0);
    LN_CHECK_EQ(rc, LN_ETIMEOUT);
    /* With LN_TAP_INCLUDE_NEWEST they start at it: 3, then what comes after. */
    ln_ring_tap* every3 = tap(seg_name, LN_TAP_EVERY | LN_TAP_INCLUDE_NEWEST);
    ln_ring_tap* newest3 = tap(seg_name, LN_TAP_NEWEST | LN_TAP_INCLUDE_NEWEST);
    LN_CHECK_EQ(tap_read(every3, 0, NULL, NULL), 3);
    LN_CHECK_EQ(tap_read(newest3, 0, NULL, NULL), 3);
    LN_CHECK_EQ(tap_read(every3, 0, NULL, &rc), 0);
    LN_CHECK_EQ(rc, LN_ETIMEOUT);
    uint64_t ov = 99;
    LN_CHECK_EQ(inject(in, 4), LN_OK);
    LN_CHECK_EQ(tap_read(every3, 0, &ov, NULL), 4);
    LN_CHECK_EQ(ov, 0);
    LN_CHECK_EQ(tap_read(newest3, 0, &ov, NULL), 4);
    LN_CHECK_EQ(ov, 0);
    ln_ring_tap_close(every3);
    ln_ring_tap_close(newest3);
    LN_CHECK_EQ(tap_read(every, 0, &ov, NULL), 4);
    LN_CHECK_EQ(ov, 0);
    LN_CHECK_EQ(tap_read(newest, 0, &ov, NULL), 4);
    LN_CHECK_EQ(ov, 0);
    /* Ten more into four slots: EVERY gets the four the ring still holds, NEWEST the last. */
    for (uint64_t i = 5; i <= 14; i++)
        LN_CHECK_EQ(inject(in, i), LN_OK);
    LN_CHECK_EQ(tap_read(newest, 0, &ov, NULL), 14);
    LN_CHECK_EQ(ov, 9);
    LN_CHECK_EQ(tap_read(newest, 0, NULL, &rc), 0);
    LN_CHECK_EQ(rc, LN_ETIMEOUT);
    LN_CHECK_EQ(tap_read(every, 0, &ov, NULL), 11);
    LN_CHECK_EQ(ov, 6);
    for (uint64_t i = 12; i <= 14; i++) {
        LN_CHECK_EQ(tap_read(every, 0, &ov, NULL), i);
        LN_CHECK_EQ(ov, 0);
    }
    LN_CHECK_EQ(tap_read(every, 0.01, NULL, &rc), 0);
    LN_CHECK_EQ(rc, LN_ETIMEOUT);
    uint8_t buf[MSG];
    LN_CHECK_EQ(ln_ring_tap_read(every, buf, NULL, NAN), LN_EINVAL);
    LN_CHECK_EQ(ln_ring_tap_read(every, NULL, NULL, 0), LN_EINVAL);
    LN_CHECK_EQ(ln_ring_tap_read(NULL, buf, NULL, 0), LN_EBADHANDLE);
    LN_CHECK_EQ(inject(in, 15), LN_OK);
    LN_CHECK_EQ(ln_ring_tap_read(every, buf, NULL, 0), LN_OK); /* info may be NULL */
    LN_CHECK_EQ(buf[0], 15);
    ln_ring_tap_close(in);
    ln_ring_tap_close(every);
    ln_ring_tap_close(newest);
    drop(a, seg_name);
}

struct blocked {
    ln_ring_tap* t;
    atomic_int started;
    int rc;
    uint64_t seq;
};

static void* blocked_reader(void* arg)
{
    struct blocked* b = arg;
    atomic_store(&b->started, 1);
    b->seq = tap_read(b->t, -1, NULL, &b->rc);
    return NULL;
}

/* Start a thread in tap_read(-1) and return once it announced that it sleeps on the ring. */
static void start_blocked(struct blocked* b, pthread_t* th, _Atomic uint32_t* futex)
{
    LN_CHECK_EQ(pthread_create(th, NULL, blocked_reader, b), 0);
    while (!atomic_load(&b->started) || !(atomic_load(futex) & LN_FUTEX_SLEEPERS))
        sched_yield();
}

static void test_blocked_read_is_woken_by_inject(void)
{
    ln_ring_admin* a = make("wake", 4);
    ln_ring_tap* in = tap(seg_name, LN_TAP_EVERY);
    ln_ring r;
    LN_CHECK_EQ(ln_ring_attach(&r, seg_name, HASH, MSG), LN_OK);
    for (unsigned mode = LN_TAP_EVERY; mode <= LN_TAP_NEWEST; mode++) {
        struct blocked b = {.t = tap(seg_name, mode)};
        pthread_t th;
        start_blocked(&b, &th, &r.hdr->data_futex);
        uint64_t n = ln_ring_tap_write_seq(in) + 3;
        LN_CHECK_EQ(inject(in, n), LN_OK);
        pthread_join(th, NULL);
        LN_CHECK_EQ(b.rc, LN_OK);
        LN_CHECK_EQ(b.seq, n);
        ln_ring_tap_close(b.t);
    }
    ln_ring_detach(&r);
    ln_ring_tap_close(in);
    drop(a, seg_name);
}

static void test_taps_follow_successors(void)
{
    char names[3][64];
    ln_ring_admin* gen[3];
    gen[0] = make("gen0", 4);
    snprintf(names[0], sizeof(names[0]), "%s", seg_name);
    ln_ring_tap* in = tap(names[0], LN_TAP_EVERY);
    ln_ring_tap* every = tap(names[0], LN_TAP_EVERY);
    ln_ring_tap* newest = tap(names[0], LN_TAP_NEWEST);
    LN_CHECK_EQ(inject(in, 1), LN_OK);
    LN_CHECK_EQ(inject(in, 2), LN_OK);
    LN_CHECK_EQ(inject(in, 4), LN_OK);
    gen[1] = make("gen1", 8);
    snprintf(names[1], sizeof(names[1]), "%s", seg_name);
    LN_CHECK_EQ(ln_ring_admin_retire(gen[0], gen[1], names[1], 1.0), LN_OK);
    LN_CHECK_STREQ(ln_ring_tap_segment(in), names[0]);
    /* Inject moves on before writing: the sample lands in the successor. */
    LN_CHECK_EQ(inject(in, 5), LN_OK);
    LN_CHECK_STREQ(ln_ring_tap_segment(in), names[1]);
    LN_CHECK_EQ(inject(in, 5), LN_EOVERRUN); /* the old ring's numbers carried over */
    /* Readers drain the old ring first, then go on in the successor without a loss. */
    LN_CHECK_EQ(ln_ring_tap_write_seq(every), 5);
    LN_CHECK_STREQ(ln_ring_tap_segment(every), names[0]);
    uint64_t ov = 99;
    LN_CHECK_EQ(tap_read(every, 0, &ov, NULL), 1);
    LN_CHECK_EQ(tap_read(every, 0, &ov, NULL), 2);
    LN_CHECK_EQ(ov, 0);
    LN_CHECK_EQ(tap_read(every, 0, &ov, NULL), 4);
    LN_CHECK_EQ(ov, 1);
    LN_CHECK_STREQ(ln_ring_tap_segment(every), names[0]);
    LN_CHECK_EQ(tap_read(every, 0, &ov, NULL), 5);
    LN_CHECK_EQ(ov, 0);
    LN_CHECK_STREQ(ln_ring_tap_segment(every), names[1]);
    /* NEWEST, like a latest subscriber, takes the old ring's newest before moving on (the
     * successor may hold no sample yet). */
    LN_CHECK_EQ(tap_read(newest, 0, &ov, NULL), 4);
    LN_CHECK_EQ(ov, 3);
    LN_CHECK_EQ(tap_read(newest, 0, &ov, NULL), 5);
    LN_CHECK_EQ(ov, 0);
    LN_CHECK_STREQ(ln_ring_tap_segment(newest), names[1]);

    /* A reader asleep on a ring that gets retired wakes, moves on and gets the next sample. */
    ln_ring r;
    LN_CHECK_EQ(ln_ring_attach(&r, names[1], HASH, MSG), LN_OK);
    struct blocked b = {.t = every};
    pthread_t th;
    start_blocked(&b, &th, &r.hdr->data_futex);
    gen[2] = make("gen2", 16);
    snprintf(names[2], sizeof(names[2]), "%s", seg_name);
    LN_CHECK_EQ(ln_ring_admin_retire(gen[1], gen[2], names[2], 1.0), LN_OK);
    LN_CHECK_EQ(inject(in, 6), LN_OK);
    pthread_join(th, NULL);
    LN_CHECK_EQ(b.rc, LN_OK);
    LN_CHECK_EQ(b.seq, 6);
    LN_CHECK_STREQ(ln_ring_tap_segment(every), names[2]);
    LN_CHECK_STREQ(ln_ring_tap_segment(in), names[2]);
    /* A tap opened on a retired ring starts on the newest generation. */
    ln_ring_tap* late = tap(names[0], LN_TAP_EVERY);
    LN_CHECK_STREQ(ln_ring_tap_segment(late), names[2]);
    LN_CHECK_EQ(ln_ring_tap_write_seq(late), 6);
    LN_CHECK_EQ(inject(in, 7), LN_OK);
    LN_CHECK_EQ(tap_read(late, 0, &ov, NULL), 7);
    LN_CHECK_EQ(tap_read(newest, 0, &ov, NULL), 7);
    LN_CHECK_EQ(ov, 1);
    ln_ring_detach(&r);
    ln_ring_tap_close(late);
    ln_ring_tap_close(in);
    ln_ring_tap_close(every);
    ln_ring_tap_close(newest);
    for (int i = 0; i < 3; i++)
        drop(gen[i], names[i]);
}

static void test_open_checks(void)
{
    ln_ring_admin* a = make("checks", 4);
    ln_ring_tap* t = NULL;
    LN_CHECK_EQ(ln_ring_tap_open(&t, seg_name, HASH + 1, MSG, LN_TAP_EVERY), LN_ELAYOUT);
    LN_CHECK(t == NULL);
    LN_CHECK(strstr(ln_last_error(), "test/tap") != NULL);
    LN_CHECK_EQ(ln_ring_tap_open(&t, seg_name, HASH, MSG + 8, LN_TAP_EVERY), LN_ELAYOUT);
    LN_CHECK_EQ(ln_ring_tap_open(&t, seg_name, HASH, MSG, 4), LN_EINVAL);
    LN_CHECK_EQ(ln_ring_tap_open(&t, seg_name, HASH, MSG, 4 | LN_TAP_INCLUDE_NEWEST), LN_EINVAL);
    LN_CHECK_EQ(ln_ring_tap_open(&t, NULL, HASH, MSG, LN_TAP_EVERY), LN_EINVAL);
    LN_CHECK_EQ(ln_ring_tap_open(NULL, seg_name, HASH, MSG, LN_TAP_EVERY), LN_EINVAL);
    LN_CHECK_EQ(ln_ring_tap_open(&t, "/ln.taptest.no.such.ring", HASH, MSG, LN_TAP_EVERY),
                LN_ENOTFOUND);
    LN_CHECK(strstr(ln_last_error(), "/ln.taptest.no.such.ring") != NULL);
    LN_CHECK(ln_ring_tap_segment(NULL) == NULL);
    LN_CHECK_EQ(ln_ring_tap_write_seq(NULL), 0);
    LN_CHECK_EQ(ln_ring_tap_slots(NULL), 0);
    ln_ring_tap_close(NULL);
    LN_CHECK_EQ(inject(NULL, 1), LN_EBADHANDLE);
    drop(a, seg_name);
}

/* A segment of `size` bytes: `fill` from `src` (NULL: zeros). */
static void raw_segment(const char* name, size_t size, const void* src, size_t fill)
{
    shm_unlink(name);
    int fd = shm_open(name, O_RDWR | O_CREAT | O_EXCL, 0600);
    LN_CHECK(fd >= 0);
    LN_CHECK_EQ(ftruncate(fd, (off_t)size), 0);
    if (src)
        LN_CHECK_EQ(write(fd, src, fill), (ssize_t)fill);
    close(fd);
}

static void test_admin_open(void)
{
    ln_ring_admin* opened = (ln_ring_admin*)1;
    LN_CHECK_EQ(ln_ring_admin_open(&opened, "/ln.taptest.no.such.ring"), LN_ENOTFOUND);
    LN_CHECK(opened == NULL);
    LN_CHECK_EQ(ln_ring_admin_open(NULL, "/x"), LN_EINVAL);

    char junk_name[64];
    snprintf(junk_name, sizeof(junk_name), "/ln.taptest%d.junk", (int)getpid());
    uint8_t junk[32768]; /* more than a ring header */
    for (size_t i = 0; i < sizeof(junk); i++)
        junk[i] = (uint8_t)(i * 131 + 7);
    raw_segment(junk_name, sizeof(junk), junk, sizeof(junk));
    LN_CHECK_EQ(ln_ring_admin_open(&opened, junk_name), LN_EPROTOCOL);
    LN_CHECK(strstr(ln_last_error(), "not a usable topic ring: no ring magic") != NULL);
    raw_segment(junk_name, 100, NULL, 0);
    LN_CHECK_EQ(ln_ring_admin_open(&opened, junk_name), LN_EPROTOCOL);
    LN_CHECK(strstr(ln_last_error(), "too small") != NULL);
    shm_unlink(junk_name);

    ln_ring_admin* a = make("adopt", 4);
    ln_ring_tap* in = tap(seg_name, LN_TAP_EVERY);
    LN_CHECK_EQ(inject(in, 9), LN_OK);
    LN_CHECK_EQ(ln_ring_admin_open(&opened, seg_name), LN_OK);
    LN_CHECK_EQ(ln_ring_admin_set_counts(opened, 3, 4), LN_OK);
    uint64_t seq = 0;
    LN_CHECK_EQ(ln_ring_admin_write_seq(opened, &seq), LN_OK);
    LN_CHECK_EQ(seq, 9);
    ln_ring r;
    LN_CHECK_EQ(ln_ring_attach(&r, seg_name, HASH, MSG), LN_OK);
    LN_CHECK_EQ(atomic_load(&r.hdr->publishers), 3);
    LN_CHECK_EQ(atomic_load(&r.hdr->subscribers), 4);
    LN_CHECK_EQ(ln_ring_admin_reserve_reader(opened, 1, getpid(), 2), LN_OK);
    LN_CHECK_EQ(atomic_load(&r.hdr->readers[1].next_seq), 10);
    ln_ring_admin_close(opened);

    /* Damage the header through the mapping: each check names what is wrong. */
    r.hdr->version = LN_RING_VERSION + 1;
    LN_CHECK_EQ(ln_ring_admin_open(&opened, seg_name), LN_EVERSION);
    LN_CHECK(strstr(ln_last_error(), "format version") != NULL);
    r.hdr->version = LN_RING_VERSION;
    r.hdr->segment_size += 4096;
    LN_CHECK_EQ(ln_ring_admin_open(&opened, seg_name), LN_EPROTOCOL);
    LN_CHECK(strstr(ln_last_error(), "recorded size") != NULL);
    r.hdr->segment_size -= 4096;
    r.hdr->header_size *= 2;
    LN_CHECK_EQ(ln_ring_admin_open(&opened, seg_name), LN_EPROTOCOL);
    LN_CHECK(strstr(ln_last_error(), "header size") != NULL);
    r.hdr->header_size /= 2;
    r.hdr->slot_count = 3;
    LN_CHECK_EQ(ln_ring_admin_open(&opened, seg_name), LN_EPROTOCOL);
    LN_CHECK(strstr(ln_last_error(), "geometry") != NULL);
    r.hdr->slot_count = 4;
    LN_CHECK_EQ(ln_ring_admin_open(&opened, seg_name), LN_OK);
    ln_ring_admin_close(opened);
    ln_ring_detach(&r);
    ln_ring_tap_close(in);
    drop(a, seg_name);
}

int main(void)
{
    LN_TEST_RUN(test_inject_keeps_seq_and_timestamp);
    LN_TEST_RUN(test_gaps_are_counted_and_skipped);
    LN_TEST_RUN(test_writer_dead_in_newest_slot_does_not_hang_readers);
    LN_TEST_RUN(test_stale_inject_changes_nothing);
    LN_TEST_RUN(test_borrow_and_release);
    LN_TEST_RUN(test_inject_in_place);
    LN_TEST_RUN(test_modes_and_start_point);
    LN_TEST_RUN(test_blocked_read_is_woken_by_inject);
    LN_TEST_RUN(test_taps_follow_successors);
    LN_TEST_RUN(test_open_checks);
    LN_TEST_RUN(test_admin_open);
    LN_TEST_EXIT();
}
