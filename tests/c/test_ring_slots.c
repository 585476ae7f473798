/* test_ring_slots.c — the ring's slot directory: large samples reuse the hottest free slot
 * (the newest's once every reader has it, else the one before) while readers keep up and
 * rotate through the ring while they lag, small samples always rotate; a latest reader's
 * borrowed sample is kept for it; whatever the schedule, a queued reader behind a waiting publisher loses nothing and
 * no sample is torn, a borrowed sample stays intact, a tap reading every sample keeps the
 * ring's whole depth, a writer killed anywhere (also between commit and directory update) is
 * recovered from, and a corrupted directory entry is an error, never an access outside the
 * ring.  Links the static libln to reach the internal ring API. */
#include <signal.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "ln_test.h"
#include "ring.h"

#define BIG LN_RING_HOT_BYTES
#define SMALL 256u
#define HASH 0x5106u
#define SLOTS 8u

static char seg_name[64];

static ln_ring_admin* make(const char* suffix, uint64_t size, uint32_t slots)
{
    snprintf(seg_name, sizeof(seg_name), "/ln.slots%d.%s", (int)getpid(), suffix);
    ln_ring_admin_unlink(seg_name);
    ln_ring_admin* a = NULL;
    LN_CHECK_EQ(ln_ring_admin_create(&a, seg_name, "slots.topic", "test/md", HASH, size, slots),
                LN_OK);
    return a;
}

static void attach(ln_ring* r, uint64_t size)
{
    LN_CHECK_EQ(ln_ring_attach(r, seg_name, HASH, size), LN_OK);
}

static void drop(ln_ring_admin* a)
{
    ln_ring_admin_close(a);
    ln_ring_admin_unlink(seg_name);
}

/* The first and last 8 bytes and one in the middle carry the value, the rest its low byte:
 * a sample torn between two writes shows up. */
static void fill(uint8_t* p, uint64_t size, uint64_t value)
{
    memset(p, (int)(value & 0xff), size);
    memcpy(p, &value, 8);
    memcpy(p + size / 2, &value, 8);
    memcpy(p + size - 8, &value, 8);
}

static int holds(const uint8_t* p, uint64_t size, uint64_t value)
{
    uint64_t a, b, c;
    memcpy(&a, p, 8);
    memcpy(&b, p + size / 2, 8);
    memcpy(&c, p + size - 8, 8);
    return a == value && b == value && c == value && p[8] == (uint8_t)(value & 0xff) &&
           p[size - 9] == (uint8_t)(value & 0xff);
}

/* Write sample write_seq+1 holding its own number; returns the slot it went to. */
static ln_ring_slot* write_next(ln_ring* r)
{
    ln_deadline d = ln_deadline_in(-1);
    LN_CHECK_EQ(ln_ring_lock(r, &d), LN_OK);
    uint64_t n = atomic_load(&r->hdr->write_seq) + 1;
    ln_ring_slot* s = ln_ring_begin(r);
    fill(ln_ring_payload(s), r->message_size, n);
    ln_ring_commit(r, s);
    ln_ring_unlock(r);
    return s;
}

/* One read by copy: the sequence number (its payload checked), 0 if none. */
static uint64_t read_one(ln_ring* r, ln_ring_cursor* c, uint8_t* buf)
{
    for (;;) {
        ln_ring_slot* s;
        uint64_t word;
        if (ln_ring_pick(r, c, &s, &word) != LN_OK)
            return 0;
        memcpy(buf, ln_ring_payload(s), r->message_size);
        if (ln_ring_finish(r, c, s, word, 1) == LN_OK) {
            LN_CHECK(holds(buf, r->message_size, LN_SLOT_SEQ(word)));
            return LN_SLOT_SEQ(word);
        }
    }
}

static ln_ring_cursor queued(ln_ring_admin* a, int index, uint32_t buffers)
{
    LN_CHECK_EQ(ln_ring_admin_reserve_reader(a, (uint32_t)index, (int32_t)getpid(), buffers),
                LN_OK);
    ln_ring_cursor c = {.next = 1, .buffers = buffers, .reader = index};
    return c;
}

/* How many different slots samples 3..20 went to, with a queued reader reading each one. */
static unsigned slots_used_when_reader_keeps_up(uint64_t size)
{
    ln_ring_admin* a = make(size >= BIG ? "hot" : "cold", size, SLOTS);
    ln_ring r;
    attach(&r, size);
    ln_ring_cursor c = queued(a, 0, SLOTS - 2);
    uint8_t* buf = malloc(size);
    ln_ring_slot* seen[SLOTS] = {0};
    unsigned used = 0;
    for (uint64_t n = 1; n <= 20; n++) {
        ln_ring_slot* s = write_next(&r);
        LN_CHECK_EQ(read_one(&r, &c, buf), n);
        int known = 0;
        for (unsigned i = 0; i < used; i++)
            known |= seen[i] == s;
        if (n >= 3 && !known && used < SLOTS)
            seen[used++] = s;
    }
    LN_CHECK_EQ(c.pending, 0);
    free(buf);
    ln_ring_detach(&r);
    drop(a);
    return used;
}

static void test_large_samples_stay_in_one_hot_slot(void)
{
    LN_CHECK_EQ(slots_used_when_reader_keeps_up(BIG), 1);
    LN_CHECK_EQ(slots_used_when_reader_keeps_up(SMALL), SLOTS);
}

static ln_ring_cursor latest_reader(ln_ring_admin* a, ln_ring* r, int index)
{
    LN_CHECK_EQ(ln_ring_admin_reserve_reader(a, (uint32_t)index, (int32_t)getpid(), 1), LN_OK);
    ln_ring_cursor c = {.next = 1, .buffers = 1, .reader = index};
    ln_ring_publish_cursor(r, &c); /* as a subscriber port does when it opens */
    return c;
}

/* A latest subscriber that has not read the newest sample keeps it: samples alternate
 * between two slots.  Once it reads each one, they stay in one. */
static void test_unread_newest_is_kept_for_a_latest_reader(void)
{
    ln_ring_admin* a = make("latest", BIG, SLOTS);
    ln_ring r;
    attach(&r, BIG);
    ln_ring_cursor c = latest_reader(a, &r, 5);
    uint8_t* buf = malloc(BIG);
    ln_ring_slot* s1 = write_next(&r);
    ln_ring_slot* s2 = write_next(&r);
    LN_CHECK(s1 != s2);
    for (int i = 0; i < 6; i++)
        LN_CHECK(write_next(&r) == (i % 2 ? s2 : s1));
    LN_CHECK_EQ(read_one(&r, &c, buf), 8);
    for (uint64_t n = 9; n < 15; n++) {
        LN_CHECK(write_next(&r) == s2); /* 8, in s2, was read: from 9 on all go there */
        LN_CHECK_EQ(read_one(&r, &c, buf), n);
    }
    free(buf);
    ln_ring_detach(&r);
    drop(a);
}

/* A latest reader's borrowed sample stays intact while the publisher writes on (up to
 * slot_count - 1 samples); held longer, its release says it was overwritten. */
static void test_latest_borrow_is_kept(void)
{
    ln_ring_admin* a = make("borrow", BIG, SLOTS);
    ln_ring r;
    attach(&r, BIG);
    ln_ring_cursor c = latest_reader(a, &r, 2);
    write_next(&r);
    ln_ring_slot* held;
    uint64_t word;
    LN_CHECK_EQ(ln_ring_pick(&r, &c, &held, &word), LN_OK);
    for (uint32_t i = 0; i < SLOTS - 1; i++) {
        write_next(&r);
        LN_CHECK(holds(ln_ring_payload(held), BIG, 1));
    }
    LN_CHECK_EQ(ln_ring_finish(&r, &c, held, word, 0), LN_OK);
    LN_CHECK_EQ(atomic_load(&r.hdr->readers[2].holding), 0);
    LN_CHECK_EQ(ln_ring_pick(&r, &c, &held, &word), LN_OK);
    uint64_t n = LN_SLOT_SEQ(word);
    for (uint32_t i = 0; i < 2 * SLOTS; i++)
        write_next(&r);
    LN_CHECK(!holds(ln_ring_payload(held), BIG, n));
    LN_CHECK_EQ(ln_ring_finish(&r, &c, held, word, 0), LN_EOVERRUN);
    ln_ring_detach(&r);
    drop(a);
}

/* A waiting publisher, a queued reader that borrows and holds samples for a while, and a
 * latest reader, in a pseudo-random order: the queued reader gets every sample in order,
 * intact, and a borrowed one never changes under it. */
static void lagging_reader_loses_nothing(uint64_t size, unsigned seed)
{
    ln_ring_admin* a = make("lag", size, SLOTS);
    ln_ring r;
    attach(&r, size);
    ln_ring_cursor q = queued(a, 3, SLOTS - 1);
    ln_ring_cursor latest = {.next = 1, .buffers = 1, .reader = -1};
    uint8_t* buf = malloc(size);
    uint64_t expect = 1, written = 0;
    ln_ring_slot* held = NULL;
    uint64_t held_word = 0;
    for (int step = 0; step < 6000; step++) {
        unsigned roll = (unsigned)rand_r(&seed) % 10;
        if (roll < 5) {
            if (ln_ring_has_space(&r)) { /* as LN_PUBLISH_WAIT_FOR_SUBSCRIBERS */
                write_next(&r);
                written++;
            }
        } else if (roll < 8) {
            if (held) {
                LN_CHECK(holds(ln_ring_payload(held), size, LN_SLOT_SEQ(held_word)));
                LN_CHECK_EQ(ln_ring_finish(&r, &q, held, held_word, 0), LN_OK);
                held = NULL;
            } else if (roll == 7 && ln_ring_pick(&r, &q, &held, &held_word) == LN_OK) {
                LN_CHECK_EQ(LN_SLOT_SEQ(held_word), expect);
                expect++;
            } else if (!held) {
                uint64_t n = read_one(&r, &q, buf);
                if (n) {
                    LN_CHECK_EQ(n, expect);
                    expect++;
                }
            }
        } else {
            uint64_t n = read_one(&r, &latest, buf);
            LN_CHECK(n == 0 || n <= written);
        }
    }
    if (held)
        LN_CHECK_EQ(ln_ring_finish(&r, &q, held, held_word, 0), LN_OK);
    while (read_one(&r, &q, buf))
        expect++;
    LN_CHECK_EQ(expect, written + 1);
    LN_CHECK_EQ(q.pending, 0);
    LN_CHECK(written > 1000);
    free(buf);
    ln_ring_detach(&r);
    drop(a);
}

static void test_lagging_reader_loses_nothing(void)
{
    for (unsigned seed = 1; seed <= 4; seed++) {
        lagging_reader_loses_nothing(BIG, seed);
        lagging_reader_loses_nothing(SMALL, seed);
    }
}

/* A tap reading every sample holds no reader slot: writers keep the whole ring for it, so it
 * can fall slot_count - 1 samples behind a reader that keeps up; closed, hot reuse resumes. */
static void test_tap_keeps_the_whole_depth(void)
{
    ln_ring_admin* a = make("tap", BIG, SLOTS);
    ln_ring r;
    attach(&r, BIG);
    ln_ring_cursor c = queued(a, 0, 2);
    uint8_t* buf = malloc(BIG);
    ln_ring_tap* tap = NULL;
    LN_CHECK_EQ(ln_ring_tap_open(&tap, seg_name, HASH, BIG, LN_TAP_EVERY), LN_OK);
    LN_CHECK_EQ(atomic_load(&r.hdr->taps), 1);
    for (uint64_t n = 1; n < SLOTS; n++) {
        write_next(&r);
        LN_CHECK_EQ(read_one(&r, &c, buf), n);
    }
    for (uint64_t n = 1; n < SLOTS; n++) {
        ln_sample_info info;
        LN_CHECK_EQ(ln_ring_tap_read(tap, buf, &info, 0), LN_OK);
        LN_CHECK_EQ(info.seq, n);
        LN_CHECK_EQ(info.overruns, 0);
        LN_CHECK(holds(buf, BIG, n));
    }
    ln_ring_tap_close(tap);
    LN_CHECK_EQ(atomic_load(&r.hdr->taps), 0);
    ln_ring_slot* first = write_next(&r);
    LN_CHECK(read_one(&r, &c, buf) > 0);
    for (int i = 0; i < 6; i++) {
        LN_CHECK(write_next(&r) == first);
        LN_CHECK(read_one(&r, &c, buf) > 0);
    }
    /* A tap reading the newest is counted once it reads: the newest is then kept for it. */
    LN_CHECK_EQ(ln_ring_tap_open(&tap, seg_name, HASH, BIG, LN_TAP_NEWEST), LN_OK);
    LN_CHECK_EQ(atomic_load(&r.hdr->newest_taps), 0);
    ln_sample_info info;
    LN_CHECK_EQ(ln_ring_tap_read(tap, buf, &info, 0), LN_ETIMEOUT);
    LN_CHECK_EQ(atomic_load(&r.hdr->newest_taps), 1);
    ln_ring_slot* other = write_next(&r);
    LN_CHECK(other != first);
    LN_CHECK(read_one(&r, &c, buf) > 0);
    LN_CHECK(write_next(&r) == first);
    ln_ring_tap_close(tap);
    LN_CHECK_EQ(atomic_load(&r.hdr->newest_taps), 0);
    free(buf);
    ln_ring_detach(&r);
    drop(a);
}

/* The tap's count moves with it into the successor when the topic's ring grows. */
static void test_tap_count_follows_the_successor(void)
{
    ln_ring_admin* a = make("old", BIG, 2);
    char old_name[64];
    snprintf(old_name, sizeof old_name, "%s", seg_name);
    ln_ring_tap* tap = NULL;
    LN_CHECK_EQ(ln_ring_tap_open(&tap, old_name, HASH, BIG, LN_TAP_EVERY), LN_OK);
    ln_ring_admin* b = make("new", BIG, 4);
    LN_CHECK_EQ(ln_ring_admin_retire(a, b, seg_name, 1.0), LN_OK);
    ln_ring fresh;
    attach(&fresh, BIG);
    write_next(&fresh);
    uint8_t* buf = malloc(BIG);
    ln_sample_info info;
    LN_CHECK_EQ(ln_ring_tap_read(tap, buf, &info, 1.0), LN_OK);
    LN_CHECK_EQ(atomic_load(&fresh.hdr->taps), 1);
    ln_ring_tap_close(tap);
    LN_CHECK_EQ(atomic_load(&fresh.hdr->taps), 0);
    free(buf);
    ln_ring_detach(&fresh);
    drop(b);
    ln_ring_admin_close(a);
    ln_ring_admin_unlink(old_name);
}

/* A writer that committed its slot and died before pointing the directory at it: the next
 * writer's recovery announces the sample from wherever it is. */
static void test_writer_killed_before_the_directory(void)
{
    ln_ring_admin* a = make("dirkill", BIG, 4);
    ln_ring r;
    attach(&r, BIG);
    ln_ring_cursor c = queued(a, 0, 3);
    uint8_t* buf = malloc(BIG);
    for (uint64_t n = 1; n <= 5; n++) {
        write_next(&r);
        LN_CHECK_EQ(read_one(&r, &c, buf), n);
    }
    pid_t pid = fork();
    if (pid == 0) {
        ln_ring w;
        if (ln_ring_attach(&w, seg_name, HASH, BIG) != LN_OK)
            _exit(2);
        ln_deadline d = ln_deadline_in(-1);
        if (ln_ring_lock(&w, &d) != LN_OK)
            _exit(3);
        ln_ring_slot* s = ln_ring_begin(&w);
        fill(ln_ring_payload(s), BIG, 6);
        atomic_store(&s->seq, LN_SLOT_WORD(6, LN_SLOT_COMMITTED)); /* commit's first step */
        kill(getpid(), SIGKILL);
        _exit(4);
    }
    int status = 0;
    waitpid(pid, &status, 0);
    LN_CHECK(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL);
    LN_CHECK_EQ(atomic_load(&r.hdr->write_seq), 5);
    write_next(&r); /* recovers 6, then writes 7 */
    LN_CHECK_EQ(read_one(&r, &c, buf), 6);
    LN_CHECK_EQ(read_one(&r, &c, buf), 7);
    LN_CHECK_EQ(c.pending, 0);
    free(buf);
    ln_ring_detach(&r);
    drop(a);
}

/* Writers killed at random points while a queued reader keeps up (hot reuse all the time):
 * no torn sample, numbers only grow, and a new writer carries on. */
static void test_writers_killed_anywhere(void)
{
    ln_ring_admin* a = make("anykill", BIG, 4);
    ln_ring r;
    attach(&r, BIG);
    ln_ring_cursor c = queued(a, 0, 3);
    uint8_t* buf = malloc(BIG);
    uint64_t last = 0;
    for (int round = 0; round < 20; round++) {
        pid_t pid = fork();
        if (pid == 0) {
            ln_ring w;
            if (ln_ring_attach(&w, seg_name, HASH, BIG) != LN_OK)
                _exit(2);
            for (;;)
                if (ln_ring_has_space(&w))
                    write_next(&w);
        }
        uint64_t target = atomic_load(&r.hdr->write_seq) + 20 + (uint64_t)(rand() % 200);
        time_t give_up = time(NULL) + 60;
        while (atomic_load(&r.hdr->write_seq) < target && time(NULL) <= give_up) {
            uint64_t n = read_one(&r, &c, buf);
            if (n) {
                LN_CHECK(n > last);
                last = n;
            }
        }
        LN_CHECK(time(NULL) <= give_up);
        kill(pid, SIGKILL);
        waitpid(pid, NULL, 0);
    }
    write_next(&r);
    uint64_t n;
    while ((n = read_one(&r, &c, buf)) != 0) {
        LN_CHECK(n > last);
        last = n;
    }
    LN_CHECK_EQ(last, atomic_load(&r.hdr->write_seq));
    free(buf);
    ln_ring_detach(&r);
    drop(a);
}

/* A directory entry pointing outside the ring: readers report it, writers pick another slot
 * and repair the entry. */
static void test_corrupted_directory_entry(void)
{
    ln_ring_admin* a = make("corrupt", BIG, 4);
    ln_ring r;
    attach(&r, BIG);
    ln_ring_cursor c = {.next = 1, .buffers = 1, .reader = -1};
    uint8_t* buf = malloc(BIG);
    write_next(&r);
    atomic_store(&r.hdr->slot_of[1], 4000u);
    ln_ring_slot* s;
    uint64_t word;
    LN_CHECK_EQ(ln_ring_pick(&r, &c, &s, &word), LN_EPROTOCOL);
    LN_CHECK(strstr(ln_last_error(), "slot directory") != NULL);
    atomic_store(&r.hdr->slot_of[2], 4000u);
    ln_ring_slot* next = write_next(&r);
    LN_CHECK((uint8_t*)next >= r.slots && (uint8_t*)next < r.slots + 4u * (uint64_t)r.stride);
    LN_CHECK_EQ(read_one(&r, &c, buf), 2);
    free(buf);
    ln_ring_detach(&r);
    drop(a);
}

int main(void)
{
    srand(20261207u); /* fixed: a failure replays the same kill points */
    LN_TEST_RUN(test_large_samples_stay_in_one_hot_slot);
    LN_TEST_RUN(test_unread_newest_is_kept_for_a_latest_reader);
    LN_TEST_RUN(test_latest_borrow_is_kept);
    LN_TEST_RUN(test_lagging_reader_loses_nothing);
    LN_TEST_RUN(test_tap_keeps_the_whole_depth);
    LN_TEST_RUN(test_tap_count_follows_the_successor);
    LN_TEST_RUN(test_writer_killed_before_the_directory);
    LN_TEST_RUN(test_writers_killed_anywhere);
    LN_TEST_RUN(test_corrupted_directory_entry);
    LN_TEST_EXIT();
}
