/* bench_common.h — code shared by the topic benchmark programs: the clock, the benchmark
 * md for a payload size, the first/last 8-byte touch of zero-copy samples, minor page
 * faults and CPU time, round-trip output for the driver and error exits.  Header-only, so
 * each program stays one translation unit. */
#ifndef LN_BENCH_COMMON_H
#define LN_BENCH_COMMON_H

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>

#include <ln/ln.h>

#include "bench_messages.h"

typedef struct bench_md {
    size_t size;
    const char* name;
    uint64_t hash;
} bench_md;

static inline uint64_t bench_now_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000000000u + (uint64_t)ts.tv_nsec;
}

/* The benchmark md whose message is exactly `size` bytes; exits if there is none. */
static inline bench_md bench_md_for(size_t size)
{
    static const bench_md table[] = {
        {sizeof(lnbench_sample_64_t), LNBENCH_SAMPLE_64_MD_NAME, LNBENCH_SAMPLE_64_LAYOUT_HASH},
        {sizeof(lnbench_sample_4k_t), LNBENCH_SAMPLE_4K_MD_NAME, LNBENCH_SAMPLE_4K_LAYOUT_HASH},
        {sizeof(lnbench_sample_64k_t), LNBENCH_SAMPLE_64K_MD_NAME, LNBENCH_SAMPLE_64K_LAYOUT_HASH},
        {sizeof(lnbench_sample_1m_t), LNBENCH_SAMPLE_1M_MD_NAME, LNBENCH_SAMPLE_1M_LAYOUT_HASH},
        {sizeof(lnbench_sample_4m_t), LNBENCH_SAMPLE_4M_MD_NAME, LNBENCH_SAMPLE_4M_LAYOUT_HASH},
        {sizeof(lnbench_sample_16m_t), LNBENCH_SAMPLE_16M_MD_NAME, LNBENCH_SAMPLE_16M_LAYOUT_HASH},
        {sizeof(lnbench_sample_64m_t), LNBENCH_SAMPLE_64M_MD_NAME, LNBENCH_SAMPLE_64M_LAYOUT_HASH},
    };
    for (size_t i = 0; i < sizeof(table) / sizeof(table[0]); i++)
        if (table[i].size == size)
            return table[i];
    fprintf(stderr, "no benchmark md of %zu bytes (64, 4096, 65536, 1, 4, 16, 64 MiB)\n", size);
    exit(2);
}

/* Minor page faults of the whole process so far (every thread). */
static inline uint64_t bench_minflt(void)
{
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    return (uint64_t)ru.ru_minflt;
}

/* CPU seconds (user + system) of the whole process so far (every thread). */
static inline double bench_cpu_s(void)
{
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    return (double)(ru.ru_utime.tv_sec + ru.ru_stime.tv_sec) +
           (double)(ru.ru_utime.tv_usec + ru.ru_stime.tv_usec) * 1e-6;
}

/* What a zero-copy sample carries: `value` in its first and in its last 8 bytes, so a
 * writer touches two pages of a large sample and a reader can tell a torn one. */
static inline void bench_stamp(void* sample, size_t size, uint64_t value)
{
    memcpy(sample, &value, sizeof value);
    memcpy((char*)sample + size - sizeof value, &value, sizeof value);
}

/* The first 8 bytes of a zero-copy sample; exits if the last 8 differ from them. */
static inline uint64_t bench_check(const void* sample, size_t size, const char* who)
{
    uint64_t first, last;
    memcpy(&first, sample, sizeof first);
    memcpy(&last, (const char*)sample + size - sizeof last, sizeof last);
    if (first != last) {
        fprintf(stderr, "%s: torn sample: first 8 bytes %llu, last 8 bytes %llu\n", who,
                (unsigned long long)first, (unsigned long long)last);
        exit(1);
    }
    return first;
}

static inline void bench_fail(const char* what, int rc)
{
    fprintf(stderr, "%s: %s: %s\n", what, ln_error_name(rc), ln_last_error());
    exit(2);
}

static inline void* bench_alloc(size_t size)
{
    void* p = aligned_alloc(64, (size + 63) / 64 * 64);
    if (!p) {
        fprintf(stderr, "out of memory (%zu bytes)\n", size);
        exit(2);
    }
    memset(p, 0x5a, size); /* touch every page before timing */
    return p;
}

/* Round trips in ns as raw little-endian uint64 values: the driver computes percentiles
 * for every transport the same way. */
static inline void bench_write_samples(const char* path, const uint64_t* rtt, size_t n)
{
    FILE* f = fopen(path, "wb");
    if (!f || fwrite(rtt, sizeof(*rtt), n, f) != n || fclose(f) != 0) {
        perror(path);
        exit(2);
    }
}

static inline void bench_ready(void)
{
    printf("ready\n");
    fflush(stdout);
}

#endif /* LN_BENCH_COMMON_H */
