/* bench_ln_log.c — what one ln_log costs a 1 kHz control loop (bench_ln_log.py runs it).
 *   bench_ln_log log|base N     The manager: $LN_MANAGER.
 * Runs N periods of 1 ms on absolute deadlines (clock_nanosleep); in each it times, with
 * CLOCK_MONOTONIC before and after, one ln_log of a formatted line ("log") or nothing
 * ("base": the cost of the timing itself).  Prints one JSON line: the per-period times in ns
 * (median, p99, max), the lines queued and dropped.  The client is created and the first
 * line logged (which starts the log queue's thread) before the loop, so the loop holds
 * only steady-state calls; a getppid() right before and after the loop marks it for strace,
 * which then shows every system call this thread makes in the loop. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include <ln/ln.h>

static int64_t ns_of(const struct timespec* t)
{
    return (int64_t)t->tv_sec * 1000000000 + t->tv_nsec;
}

static int cmp(const void* a, const void* b)
{
    int64_t x = *(const int64_t*)a, y = *(const int64_t*)b;
    return x < y ? -1 : x > y;
}

int main(int argc, char** argv)
{
    if (argc != 3 || (strcmp(argv[1], "log") != 0 && strcmp(argv[1], "base") != 0)) {
        fprintf(stderr, "usage: bench_ln_log log|base N\n");
        return 2;
    }
    int logging = strcmp(argv[1], "log") == 0;
    long n = strtol(argv[2], NULL, 10);
    int64_t* cost = calloc((size_t)n, sizeof *cost);
    ln_client* clnt = NULL;
    if (cost == NULL || n < 1 || ln_client_create(&clnt, "bench_ln_log", NULL) != LN_OK) {
        fprintf(stderr, "bench_ln_log: %s\n", ln_last_error());
        return 1;
    }
    ln_log(clnt, LN_LOG_INFO, "bench_ln_log starts"); /* starts the queue and its thread */
    ln_log_flush(clnt, 10.0);
    struct timespec next, t0, t1;
    clock_gettime(CLOCK_MONOTONIC, &next);
    double position = 0.0;
    (void)getppid(); /* the loop starts (a marker for strace) */
    for (long i = 0; i < n; i++) {
        next.tv_nsec += 1000000;
        if (next.tv_nsec >= 1000000000) {
            next.tv_sec++;
            next.tv_nsec -= 1000000000;
        }
        clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, NULL);
        position += 0.001;
        clock_gettime(CLOCK_MONOTONIC, &t0);
        if (logging)
            ln_log(clnt, LN_LOG_INFO, "period %ld: joint position %.3f rad", i, position);
        clock_gettime(CLOCK_MONOTONIC, &t1);
        cost[i] = ns_of(&t1) - ns_of(&t0);
    }
    (void)getppid(); /* the loop ended */
    uint64_t queued = 0, dropped = 0;
    ln_log_flush(clnt, 10.0);
    ln_log_counts(clnt, &queued, &dropped);
    qsort(cost, (size_t)n, sizeof *cost, cmp);
    printf("{\"mode\": \"%s\", \"n\": %ld, \"median_ns\": %lld, \"p99_ns\": %lld, "
           "\"max_ns\": %lld, \"queued\": %llu, \"dropped\": %llu}\n",
           argv[1], n, (long long)cost[n / 2], (long long)cost[(n * 99) / 100],
           (long long)cost[n - 1], (unsigned long long)queued, (unsigned long long)dropped);
    ln_client_destroy(clnt);
    free(cost);
    return 0;
}
