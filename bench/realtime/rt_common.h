/* rt_common.h — what the real-time benchmark programs (rt_ln, rt_futex, rt_iox) share: the
 * two message shapes (a 64 B ping-pong, the demo robot's joint_state -> command pair), memory
 * locking, the periodic ping loop on absolute clock_nanosleep deadlines, the echo loop, and
 * the JSON line each side prints about how it really ran (policy, priority, CPUs, mlockall,
 * page faults).  Header-only: each program stays one translation unit. */
#ifndef LN_RT_COMMON_H
#define LN_RT_COMMON_H

#include <errno.h>
#include <inttypes.h>
#include <sched.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <time.h>

#include "rt_messages.h"

#define RT_MAX_SIZE 4096

/* pingpong: 64 B both ways; control: joint_state out (ping = the 1 kHz arm), command back
 * (pong = the controller), as examples/robot. */
typedef struct rt_shape {
    const char* name;
    size_t out_size, back_size;
} rt_shape;

static inline rt_shape rt_shape_of(const char* name)
{
    if (strcmp(name, "pingpong") == 0)
        return (rt_shape){"pingpong", sizeof(lnbench_sample_64_t), sizeof(lnbench_sample_64_t)};
    if (strcmp(name, "control") == 0)
        return (rt_shape){"control", sizeof(robot_joint_state_t), sizeof(robot_command_t)};
    fprintf(stderr, "unknown shape '%s' (pingpong or control)\n", name);
    exit(2);
}

/* One transport: send `counter` in the first 8 bytes of a message of `size`; wait for the next
 * message and return its counter. */
typedef struct rt_ops {
    void (*send)(void* ctx, uint64_t counter, size_t size);
    uint64_t (*receive)(void* ctx, size_t size);
} rt_ops;

typedef struct rt_status {
    int mlock_errno; /* 0: mlockall(MCL_CURRENT | MCL_FUTURE) succeeded */
    uint64_t minflt_start;
    uint64_t overruns; /* cycles that ended after the next deadline */
} rt_status;

static inline uint64_t rt_now_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000000000u + (uint64_t)ts.tv_nsec;
}

static inline uint64_t rt_minflt(void)
{
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    return (uint64_t)ru.ru_minflt;
}

/* Lock every page now and later (libln and ln_daemon do not: it is the program's call), and
 * touch a stack reserve so the loop never faults a stack page in. */
static inline void rt_lock_memory(rt_status* st)
{
    st->mlock_errno = mlockall(MCL_CURRENT | MCL_FUTURE) == 0 ? 0 : errno;
    volatile unsigned char stack[64 * 1024];
    memset((void*)stack, 0, sizeof stack);
}

/* One JSON line: how this side ran; the driver reports it beside the numbers. */
static inline void rt_print_status(const char* role, const rt_status* st, uint64_t samples)
{
    int policy = sched_getscheduler(0);
    struct sched_param sp = {0};
    sched_getparam(0, &sp);
    cpu_set_t set;
    char cpus[256] = "";
    if (sched_getaffinity(0, sizeof set, &set) == 0)
        for (int c = 0, n = 0; c < CPU_SETSIZE && n < 200; c++)
            if (CPU_ISSET(c, &set))
                n += snprintf(cpus + n, sizeof cpus - (size_t)n, "%s%d", n ? "," : "", c);
    printf("{\"role\": \"%s\", \"policy\": \"%s\", \"priority\": %d, \"cpus\": \"%s\", "
           "\"mlockall\": \"%s\", \"minflt\": %" PRIu64 ", \"overruns\": %" PRIu64
           ", \"samples\": %" PRIu64 "}\n",
           role,
           policy == SCHED_FIFO ? "SCHED_FIFO"
           : policy == SCHED_RR ? "SCHED_RR"
                                : "SCHED_OTHER",
           sp.sched_priority, cpus, st->mlock_errno ? strerror(st->mlock_errno) : "ok",
           rt_minflt() - st->minflt_start, st->overruns, samples);
    fflush(stdout);
}

static inline void rt_ready(void)
{
    printf("ready\n");
    fflush(stdout);
}

static inline void rt_add_ns(struct timespec* t, uint64_t ns)
{
    uint64_t total = (uint64_t)t->tv_nsec + ns;
    t->tv_sec += (time_t)(total / 1000000000u);
    t->tv_nsec = (long)(total % 1000000000u);
}

/* The periodic side: every 1/rate s (absolute deadlines, CLOCK_MONOTONIC) wake, send, wait for
 * the answer.  Writes two little-endian uint64 per counted cycle to `out`: the round trip (ns,
 * from the wake-up) and the wake-up's lateness behind its deadline (ns), from which the driver
 * computes the loop period's jitter.  A late cycle keeps the grid (it is counted, not hidden). */
static inline int rt_ping(const rt_ops* ops, void* ctx, const rt_shape* shape, double rate,
                          uint64_t count, uint64_t warmup, const char* out)
{
    rt_status st = {0};
    uint64_t* rec = calloc(2 * (count ? count : 1), sizeof(uint64_t));
    if (!rec) {
        fputs("rt: out of memory\n", stderr);
        return 2;
    }
    memset(rec, 0, 2 * (count ? count : 1) * sizeof(uint64_t)); /* touch before locking */
    rt_lock_memory(&st);
    uint64_t period = (uint64_t)(1e9 / rate);
    struct timespec next;
    clock_gettime(CLOCK_MONOTONIC, &next);
    rt_add_ns(&next, period);
    for (uint64_t i = 0; i < warmup + count; i++) {
        if (i == warmup) {
            st.minflt_start = rt_minflt();
            st.overruns = 0;
        }
        while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, NULL) == EINTR) {
        }
        uint64_t deadline = (uint64_t)next.tv_sec * 1000000000u + (uint64_t)next.tv_nsec;
        uint64_t t0 = rt_now_ns();
        ops->send(ctx, i, shape->out_size);
        uint64_t got = ops->receive(ctx, shape->back_size);
        uint64_t t1 = rt_now_ns();
        if (got != i) {
            fprintf(stderr, "rt: cycle %" PRIu64 " came back as %" PRIu64 "\n", i, got);
            return 1;
        }
        if (i >= warmup) {
            rec[2 * (i - warmup)] = t1 - t0;
            rec[2 * (i - warmup) + 1] = t0 > deadline ? t0 - deadline : 0;
        }
        rt_add_ns(&next, period);
        if (t1 > deadline + period)
            st.overruns++;
    }
    rt_print_status("ping", &st, count);
    FILE* f = fopen(out, "wb");
    if (!f || fwrite(rec, sizeof(uint64_t), 2 * count, f) != 2 * count || fclose(f) != 0) {
        perror(out);
        return 2;
    }
    free(rec);
    return 0;
}

/* The echo side: `total` times wait for a message and send its counter back. */
static inline int rt_pong(const rt_ops* ops, void* ctx, const rt_shape* shape, uint64_t total,
                          uint64_t warmup)
{
    rt_status st = {0};
    rt_lock_memory(&st);
    rt_ready();
    for (uint64_t i = 0; i < total; i++) {
        if (i == warmup)
            st.minflt_start = rt_minflt();
        ops->send(ctx, ops->receive(ctx, shape->out_size), shape->back_size);
    }
    rt_print_status("pong", &st, total > warmup ? total - warmup : 0);
    return 0;
}

#endif /* LN_RT_COMMON_H */
