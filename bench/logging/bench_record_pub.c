/* bench_record_pub.c — the publishers of the recording rate benchmark (bench_record_rates.py):
 * N topics PREFIX.0 … PREFIX.N-1 of md lnbench/record_1k (1 KiB), each with its own queue of
 * BUFFERS.  Prints "ready", waits until every topic has a subscriber, prints "subscribed",
 * then on "go HZ SECONDS" publishes every topic at HZ for SECONDS (all topics once per
 * period, each sample written in full), answers one JSON line and exits on "quit". */
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/prctl.h>
#include <time.h>

#include <ln/ln.h>

#include "record_messages.h"

static const char usage[] = "usage: bench_record_pub PREFIX N BUFFERS   (manager: $LN_MANAGER)\n";

static uint64_t now_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000000000u + (uint64_t)ts.tv_nsec;
}

static void fail(const char* what, int rc)
{
    fprintf(stderr, "bench_record_pub: %s: %s\n", what, ln_strerror(rc));
    exit(1);
}

static void sleep_until(uint64_t deadline)
{
    struct timespec ts = {(time_t)(deadline / 1000000000u), (long)(deadline % 1000000000u)};
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, NULL) != 0)
        ;
}

/* Every field of the sample, from the topic and its counter. */
static void fill(lnbench_record_1k_t* s, uint32_t topic, uint64_t counter)
{
    s->counter = counter;
    snprintf(s->frame_id, sizeof s->frame_id, "link_%u", topic);
    for (int j = 0; j < 40; j++) {
        double x = (double)counter * 1e-3 + j;
        s->q[j] = sin(x);
        s->dq[j] = cos(x);
        s->tau[j] = (float)(x * 0.5);
    }
    for (int j = 0; j < 48; j++)
        s->mode[j] = (int32_t)((counter + (uint64_t)j) % 7);
}

static void run(ln_outport** pubs, uint32_t n, double hz, double seconds)
{
    uint64_t period = (uint64_t)(1e9 / hz), rounds = (uint64_t)(hz * seconds), late = 0;
    lnbench_record_1k_t sample;
    uint64_t t0 = now_ns(), due = t0;
    for (uint64_t i = 0; i < rounds; i++) {
        if (now_ns() > due + period) {
            late++; /* not scheduled in time: go on from now, never in a burst */
            due = now_ns();
        } else {
            sleep_until(due);
        }
        for (uint32_t t = 0; t < n; t++) {
            fill(&sample, t, i);
            int rc = ln_write(pubs[t], &sample, sizeof sample, -1);
            if (rc < 0)
                fail("ln_write", rc);
        }
        due += period;
    }
    double took = (double)(now_ns() - t0) / 1e9;
    printf("{\"published_per_topic\": %" PRIu64 ", \"topics\": %u, \"seconds\": %.3f, "
           "\"late_periods\": %" PRIu64 "}\n",
           rounds, n, took, late);
}

int main(int argc, char** argv)
{
    if (argc != 4) {
        fputs(usage, stderr);
        return 2;
    }
    uint32_t n = (uint32_t)strtoul(argv[2], NULL, 10);
    ln_port_options opts;
    ln_port_options_init(&opts);
    opts.buffers = (uint32_t)strtoul(argv[3], NULL, 10);
    prctl(PR_SET_TIMERSLACK, 1000UL);
    ln_client* clnt;
    int rc = ln_client_create(&clnt, "bench_record_pub", NULL);
    if (rc < 0)
        fail("ln_client_create", rc);
    ln_outport** pubs = calloc(n, sizeof *pubs);
    if (!pubs)
        return 1;
    char topic[256];
    for (uint32_t t = 0; t < n; t++) {
        snprintf(topic, sizeof topic, "%s.%u", argv[1], t);
        rc = ln_publish(clnt, &pubs[t], topic, LNBENCH_RECORD_1K_MD_NAME,
                        LNBENCH_RECORD_1K_LAYOUT_HASH, sizeof(lnbench_record_1k_t), &opts);
        if (rc < 0)
            fail("ln_publish", rc);
    }
    printf("ready\n");
    fflush(stdout);
    for (uint32_t t = 0; t < n; t++)
        while (ln_outport_subscriber_count(pubs[t]) < 1)
            sleep_until(now_ns() + 10000000u);
    printf("subscribed\n");
    fflush(stdout);
    char line[256];
    double hz, seconds;
    while (fgets(line, sizeof line, stdin)) {
        if (sscanf(line, "go %lf %lf", &hz, &seconds) == 2 && hz > 0)
            run(pubs, n, hz, seconds);
        else if (strncmp(line, "quit", 4) == 0)
            break;
        else
            printf("{\"error\": \"unknown command\"}\n");
        fflush(stdout);
    }
    ln_client_destroy(clnt);
    free(pubs);
    return 0;
}
