/* bench_logger_pub.c — the publisher of the topic logger benchmark (bench_logger.py): publishes
 * one topic of a benchmark md with BUFFERS buffers (a ring of BUFFERS + 1 slots), prints
 * "ready MD_NAME LAYOUT_HASH", then answers commands on stdin with one JSON line each:
 *   cost COUNT       ns per ln_write over COUNT writes in a tight loop (after a warm-up)
 *   rate HZ SECONDS  publish at HZ for SECONDS, never in a burst: how many, how fast
 *   quit
 * The driver switches the daemon's logger between the commands. */
#include <inttypes.h>
#include <sys/prctl.h>

#include "bench_common.h"

static const char usage[] = "usage: bench_logger_pub TOPIC SIZE BUFFERS   (manager: $LN_MANAGER)\n";

static void write_one(ln_outport* pub, uint8_t* src, size_t size, uint64_t i)
{
    memcpy(src, &i, sizeof i);
    int rc = ln_write(pub, src, size, -1);
    if (rc < 0)
        bench_fail("ln_write", rc);
}

static void cost(ln_outport* pub, uint8_t* src, size_t size, uint64_t count)
{
    for (uint64_t i = 0; i < count / 10 + 1; i++) /* warm-up */
        write_one(pub, src, size, i);
    uint64_t t0 = bench_now_ns();
    for (uint64_t i = 0; i < count; i++)
        write_one(pub, src, size, i);
    double ns = (double)(bench_now_ns() - t0) / (double)count;
    printf("{\"ns_per_write\": %.2f, \"count\": %" PRIu64 "}\n", ns, count);
}

/* Sleeps until `deadline` (CLOCK_MONOTONIC ns): clock_nanosleep for all but the last 30 µs,
 * then polls, so the schedule holds at high rates as well. */
static void wait_until(uint64_t deadline)
{
    uint64_t now = bench_now_ns();
    if (deadline > now + 30000) {
        uint64_t wake = deadline - 30000;
        struct timespec ts = {(time_t)(wake / 1000000000u), (long)(wake % 1000000000u)};
        clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, NULL);
    }
    while (bench_now_ns() < deadline)
        ;
}

/* Writes at least a period apart, never in a burst: after a write that came late (the
 * publisher was not scheduled in time) the schedule goes on from that write, so what a
 * logger misses is its own doing. */
static void rate(ln_outport* pub, uint8_t* src, size_t size, double hz, double seconds)
{
    uint64_t period = (uint64_t)(1e9 / hz);
    uint64_t count = (uint64_t)(hz * seconds);
    if (count == 0)
        count = 1;
    uint64_t late = 0; /* writes that started more than a period behind the schedule */
    uint64_t t0 = bench_now_ns(), due = t0;
    for (uint64_t i = 0; i < count; i++) {
        uint64_t now = bench_now_ns();
        if (now > due + period) {
            late++;
            due = now;
        } else {
            wait_until(due);
        }
        write_one(pub, src, size, i);
        due += period;
    }
    double took = (double)(bench_now_ns() - t0) / 1e9;
    printf("{\"published\": %" PRIu64 ", \"seconds\": %.4f, \"achieved_hz\": %.1f, "
           "\"late\": %" PRIu64 "}\n",
           count, took, (double)count / took, late);
}

int main(int argc, char** argv)
{
    if (argc != 4) {
        fputs(usage, stderr);
        return 2;
    }
    bench_md md = bench_md_for(strtoull(argv[2], NULL, 10));
    ln_port_options opts;
    ln_port_options_init(&opts);
    opts.buffers = (uint32_t)strtoul(argv[3], NULL, 10);
    prctl(PR_SET_TIMERSLACK, 1000UL); /* 1 µs: the rate schedule's sleeps end on time */
    ln_client* clnt;
    ln_outport* pub;
    int rc = ln_client_create(&clnt, "bench_logger_pub", NULL);
    if (rc < 0)
        bench_fail("ln_client_create", rc);
    if ((rc = ln_publish(clnt, &pub, argv[1], md.name, md.hash, md.size, &opts)) < 0)
        bench_fail("ln_publish", rc);
    uint8_t* src = bench_alloc(md.size);
    printf("ready %s %" PRIu64 "\n", md.name, md.hash);
    fflush(stdout);
    char line[256];
    while (fgets(line, sizeof line, stdin)) {
        uint64_t count;
        double hz, seconds;
        if (sscanf(line, "cost %" SCNu64, &count) == 1)
            cost(pub, src, md.size, count);
        else if (sscanf(line, "rate %lf %lf", &hz, &seconds) == 2 && hz > 0)
            rate(pub, src, md.size, hz, seconds);
        else if (strncmp(line, "quit", 4) == 0)
            break;
        else
            printf("{\"error\": \"unknown command\"}\n");
        fflush(stdout);
    }
    ln_client_destroy(clnt);
    return 0;
}
