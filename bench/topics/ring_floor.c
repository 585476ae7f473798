/* ring_floor.c — the floor under zero-copy topics: rings of N slots in one POSIX shared memory
 * segment, written and read in place (zc: the first and last 8 bytes of a slot; full: a whole
 * source buffer copied into the slot, the slot copied out whole, the echo copying a received
 * slot into its own), with the notification libln uses (spin with sched_yield, then a futex
 * woken only when someone sleeps).  This process is ping / publisher, a forked child pong /
 * subscriber. */
#include <errno.h>
#include <fcntl.h>
#include <inttypes.h>
#include <linux/futex.h>
#include <sched.h>
#include <signal.h>
#include <stdatomic.h>
#include <sys/mman.h>
#include <sys/prctl.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include "bench_common.h"

static const char usage[] =
    "usage: ring_floor lat SIZE COUNT WARMUP OUT [PONG_CPU] [zc|full]  COUNT round trips (ns)\n"
    "       ring_floor thr SIZE COUNT SLOTS WARM SECONDS [zc|full]  until COUNT or SECONDS\n"
    "zc (default): the first and last 8 bytes of a slot; full: the whole payload copied in\n"
    "and out.  One JSON line: minor faults of both sides from round trip WARMUP / sample\n"
    "WARM on; lat writes its round trips to OUT.\n";

#define SLEEPER 0x80000000u /* in a futex word: someone sleeps on it */
#define SPIN_NS 20000u      /* as libln's default spin_us */

/* One direction: the writer's and the reader's sequence numbers (31 bits, then the sleeper
 * bit), each on its own cache line, then `slots` slots of `stride` bytes. */
typedef struct ring {
    _Alignas(64) _Atomic uint32_t head; /* samples written; the reader sleeps on it */
    _Alignas(64) _Atomic uint32_t tail; /* samples read; a writer of a full ring sleeps on it */
    _Alignas(64) uint32_t slots;
    uint64_t stride, offset; /* of slot 0 from the start of the segment */
} ring;

typedef struct shared {
    ring ring[2];
    _Atomic uint64_t child_faults, child_samples, child_elapsed_ns; /* for the report */
} shared;

static uint8_t* base;

static void futex(_Atomic uint32_t* word, int op, uint32_t value)
{
    syscall(SYS_futex, (uint32_t*)word, op, value, NULL, NULL, 0);
}

/* Wait until (*word & ~SLEEPER) != seen: spin, then set the sleeper bit and sleep.  The
 * seq_cst fetch_or and the other side's seq_cst exchange make a lost wake-up impossible. */
static uint32_t wait_change(_Atomic uint32_t* word, uint32_t seen)
{
    uint64_t until = 0;
    for (;;) {
        uint32_t v = atomic_load_explicit(word, memory_order_acquire) & ~SLEEPER;
        if (v != seen)
            return v;
        if (until == 0)
            until = bench_now_ns() + SPIN_NS;
        if (bench_now_ns() < until) {
            sched_yield();
            continue;
        }
        uint32_t old = atomic_fetch_or(word, SLEEPER);
        if ((old & ~SLEEPER) == seen)
            futex(word, FUTEX_WAIT, old | SLEEPER);
    }
}

static void advance(_Atomic uint32_t* word, uint32_t value)
{
    if (atomic_exchange(word, value & ~SLEEPER) & SLEEPER)
        futex(word, FUTEX_WAKE, 1);
}

static uint8_t* slot(const ring* r, uint32_t n)
{
    return base + r->offset + (uint64_t)(n % r->slots) * r->stride;
}

/* The slot to write next (a loan), waiting while the ring is full; publish() commits it. */
static uint8_t* reserve(ring* r)
{
    uint32_t head = atomic_load_explicit(&r->head, memory_order_relaxed) & ~SLEEPER;
    uint32_t tail = atomic_load_explicit(&r->tail, memory_order_acquire) & ~SLEEPER;
    while (((head - tail) & ~SLEEPER) >= r->slots)
        tail = wait_change(&r->tail, tail);
    return slot(r, head);
}

static void publish(ring* r)
{
    uint32_t head = atomic_load_explicit(&r->head, memory_order_relaxed) & ~SLEEPER;
    advance(&r->head, (head + 1) & ~SLEEPER);
}

/* The next sample's slot (a borrow), once there is one; release() frees it. */
static const uint8_t* peek(ring* r)
{
    uint32_t tail = atomic_load_explicit(&r->tail, memory_order_relaxed) & ~SLEEPER;
    if ((atomic_load_explicit(&r->head, memory_order_acquire) & ~SLEEPER) == tail)
        wait_change(&r->head, tail);
    return slot(r, tail);
}

static void release(ring* r)
{
    uint32_t tail = atomic_load_explicit(&r->tail, memory_order_relaxed) & ~SLEEPER;
    advance(&r->tail, (tail + 1) & ~SLEEPER);
}

/* Publish `value` in the next slot: stamped in place, or (src) copied whole from src after
 * stamping it there. */
static void put(ring* r, size_t size, uint64_t value, uint8_t* src)
{
    uint8_t* s = reserve(r);
    if (src) {
        bench_stamp(src, size, value);
        memcpy(s, src, size);
    } else {
        bench_stamp(s, size, value);
    }
    publish(r);
}

/* The next sample's value; with dst, the whole slot is copied there before it is freed. */
static uint64_t get(ring* r, size_t size, uint8_t* dst)
{
    const uint8_t* s = peek(r);
    if (dst)
        memcpy(dst, s, size);
    uint64_t value = dst ? 0 : bench_check(s, size, "ring_floor");
    release(r);
    return dst ? bench_check(dst, size, "ring_floor") : value;
}

/* The echo of the full mode: the received slot copied whole into the next slot out. */
static void forward(ring* in, ring* out, size_t size)
{
    const uint8_t* s = peek(in);
    uint8_t* d = reserve(out);
    memcpy(d, s, size);
    release(in);
    bench_check(d, size, "ring_floor");
    publish(out);
}

/* One segment for both rings: created, mapped and unlinked at once (the child inherits
 * the mapping), its pages reserved as libln's manager does. */
static shared* map_segment(size_t size, uint32_t slots)
{
    size_t stride = (size + 63) / 64 * 64, head = (sizeof(shared) + 4095) / 4096 * 4096;
    size_t len = head + 2 * (size_t)slots * stride;
    char name[64];
    snprintf(name, sizeof name, "/ln_bench_floor.%d", (int)getpid());
    int fd = shm_open(name, O_RDWR | O_CREAT | O_EXCL, 0600);
    if (fd < 0) {
        perror("ring_floor: shm_open");
        exit(2);
    }
    shm_unlink(name);
    int err = ftruncate(fd, (off_t)len) != 0 ? errno : posix_fallocate(fd, 0, (off_t)len);
    base = err ? MAP_FAILED : mmap(NULL, len, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
    close(fd);
    if (base == MAP_FAILED) {
        fprintf(stderr, "ring_floor: segment of %zu bytes: %s\n", len, strerror(err ? err : errno));
        exit(2);
    }
    shared* s = (shared*)base;
    for (int i = 0; i < 2; i++)
        s->ring[i] = (ring){.slots = slots, .stride = stride, .offset = head + i * slots * stride};
    return s;
}

static void pin(const char* cpu)
{
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(atoi(cpu), &set);
    if (sched_setaffinity(0, sizeof set, &set) != 0) {
        perror("ring_floor: sched_setaffinity");
        _exit(2);
    }
}

static pid_t spawn(void)
{
    pid_t child = fork();
    if (child < 0) {
        perror("ring_floor: fork");
        exit(2);
    }
    if (child == 0)
        prctl(PR_SET_PDEATHSIG, SIGKILL);
    return child;
}

static int reap(pid_t child)
{
    int status = 0;
    waitpid(child, &status, 0);
    return WIFEXITED(status) && WEXITSTATUS(status) == 0 ? 0 : 1;
}

static int latency(int argc, char** argv, size_t size, int full)
{
    uint64_t count = strtoull(argv[3], NULL, 10), warmup = strtoull(argv[4], NULL, 10);
    shared* s = map_segment(size, 2); /* two slots each way, as a latest ln topic */
    pid_t pong = spawn();
    if (pong == 0) {
        if (argc == 7)
            pin(argv[6]);
        uint64_t faults = 0;
        for (uint64_t i = 0; i < warmup + count; i++) {
            if (i == warmup)
                faults = bench_minflt();
            if (full)
                forward(&s->ring[0], &s->ring[1], size);
            else
                put(&s->ring[1], size, get(&s->ring[0], size, NULL), NULL);
        }
        s->child_faults = bench_minflt() - faults;
        s->child_samples = count;
        _exit(0);
    }
    /* after the fork, so that writing it does not take copy-on-write faults */
    uint64_t* rtt = bench_alloc((count ? count : 1) * sizeof(uint64_t));
    uint8_t* src = full ? bench_alloc(size) : NULL;
    uint8_t* reply = full ? bench_alloc(size) : NULL;
    uint64_t faults = 0;
    for (uint64_t i = 0; rtt && i < warmup + count; i++) {
        if (i == warmup)
            faults = bench_minflt();
        uint64_t t0 = bench_now_ns();
        put(&s->ring[0], size, i, src);
        uint64_t got = get(&s->ring[1], size, reply);
        uint64_t t1 = bench_now_ns();
        if (got != i) {
            fprintf(stderr, "ring_floor: round trip %" PRIu64 " came back as %" PRIu64 "\n", i,
                    got);
            return 1;
        }
        if (i >= warmup)
            rtt[i - warmup] = t1 - t0;
    }
    faults = bench_minflt() - faults;
    int rc = reap(pong);
    bench_write_samples(argv[5], rtt, count);
    printf("{\"ping_minflt\": %" PRIu64 ", \"pong_minflt\": %" PRIu64 ", \"samples\": %" PRIu64
           "}\n",
           faults, (uint64_t)s->child_faults, count);
    return rc;
}

static int throughput(char** argv, size_t size, int full)
{
    uint64_t count = strtoull(argv[3], NULL, 10), warm = strtoull(argv[5], NULL, 10);
    double seconds = atof(argv[6]);
    shared* s = map_segment(size, (uint32_t)strtoul(argv[4], NULL, 10));
    ring* r = &s->ring[0];
    pid_t sub = spawn();
    if (sub == 0) {
        uint64_t received = 0, faults = 0, counted = 0, t0 = 0, value;
        uint8_t* dst = full ? bench_alloc(size) : NULL;
        do {
            value = get(r, size, dst);
            if (received++ == 0)
                t0 = bench_now_ns();
            if (!counted && value >= warm)
                faults = bench_minflt();
            counted += counted || value >= warm;
        } while (value + 1 < count);
        s->child_elapsed_ns = bench_now_ns() - t0;
        s->child_faults = counted ? bench_minflt() - faults : 0;
        s->child_samples = counted;
        _exit(0);
    }
    uint8_t* src = full ? bench_alloc(size) : NULL;
    uint64_t t0 = bench_now_ns(), faults = bench_minflt(), sent = 0;
    uint64_t stop_ns = seconds > 0 ? t0 + (uint64_t)(seconds * 1e9) : UINT64_MAX;
    for (uint64_t i = 0; i < count; i++) {
        if (i == warm)
            faults = bench_minflt();
        int last = (i & 15) == 0 && bench_now_ns() > stop_ns;
        put(r, size, last ? count - 1 : i, src);
        sent++;
        if (last)
            break;
    }
    uint64_t t1 = bench_now_ns();
    faults = sent > warm ? bench_minflt() - faults : 0;
    int rc = reap(sub);
    printf("{\"sent\": %" PRIu64 ", \"received\": %" PRIu64 ", \"elapsed_s\": %.9f"
           ", \"send_elapsed_s\": %.9f, \"pub_minflt\": %" PRIu64 ", \"sub_minflt\": %" PRIu64
           ", \"fault_samples\": %" PRIu64 "}\n",
           sent, sent, (double)s->child_elapsed_ns * 1e-9, (double)(t1 - t0) * 1e-9, faults,
           (uint64_t)s->child_faults, (uint64_t)s->child_samples);
    return rc;
}

int main(int argc, char** argv)
{
    /* an optional payload mode after the arguments */
    int full = argc > 1 && strcmp(argv[argc - 1], "full") == 0;
    if (full || (argc > 1 && strcmp(argv[argc - 1], "zc") == 0))
        argc--;
    int lat = argc >= 6 && argc <= 7 && strcmp(argv[1], "lat") == 0;
    int thr = argc == 7 && strcmp(argv[1], "thr") == 0;
    if (!lat && !thr) {
        fputs(usage, stderr);
        return 2;
    }
    size_t size = strtoull(argv[2], NULL, 10);
    if (size < 16) {
        fputs("ring_floor: SIZE must be at least 16\n", stderr);
        return 2;
    }
    return lat ? latency(argc, argv, size, full) : throughput(argv, size, full);
}
