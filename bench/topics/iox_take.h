/* iox_take.h — how the iceoryx peers of the benchmarks (iox_bench, bench/realtime's rt_iox)
 * wait for a chunk, the way libln's readers do: poll it (yielding the CPU) for spin_ns,
 * then sleep in the subscriber's WaitSet.  Include after the iceoryx binding headers. */
#ifndef LN_BENCH_IOX_TAKE_H
#define LN_BENCH_IOX_TAKE_H

#include <sched.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

static inline uint64_t iox_take_now_ns(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (uint64_t)t.tv_sec * 1000000000u + (uint64_t)t.tv_nsec;
}

/* The next chunk of `sub`, not yet released; NULL after `timeout_s` without one.  Exits
 * (status 2, naming `who`) if iceoryx reports an error. */
static inline const void* iox_take_chunk(iox_sub_t sub, iox_ws_t ws, uint64_t spin_ns,
                                         double timeout_s, const char* who)
{
    const void* chunk;
    uint64_t spin_until = 0;
    for (;;) {
        enum iox_ChunkReceiveResult rc = iox_sub_take_chunk(sub, &chunk);
        if (rc == ChunkReceiveResult_SUCCESS)
            return chunk;
        if (rc != ChunkReceiveResult_NO_CHUNK_AVAILABLE) {
            fprintf(stderr, "%s: iox_sub_take_chunk failed (%d)\n", who, (int)rc);
            exit(2);
        }
        uint64_t now = iox_take_now_ns();
        if (spin_until == 0)
            spin_until = now + spin_ns;
        if (now < spin_until) {
            sched_yield();
            continue;
        }
        iox_notification_info_t info[1];
        uint64_t missed = 0;
        struct timespec t = {(time_t)timeout_s, (long)((timeout_s - (time_t)timeout_s) * 1e9)};
        if (iox_ws_timed_wait(ws, t, info, 1, &missed) == 0 && !iox_sub_has_chunks(sub))
            return NULL;
    }
}

#endif /* LN_BENCH_IOX_TAKE_H */
