/* waitset_bench.c — the C processes of the waitset benchmark (bench/waitset/bench_waitset.py):
 * a publisher that writes stamped 64 B samples at a fixed pace (timing its ln_write), a
 * subscriber that waits for them with a blocking ln_read or through a waitset of N attached
 * inports and times each one-way, and an idle process that waits on inports and a 1 s timer
 * (or only sleeps) while its CPU time is counted.  Manager from $LN_MANAGER. */
#include <errno.h>
#include <inttypes.h>
#include <stddef.h>

#include "bench_common.h"

static const char usage[] =
    "usage: waitset_bench pub TOPIC COUNT PERIOD_US\n"
    "           COUNT samples, one every PERIOD_US, each stamped with CLOCK_MONOTONIC\n"
    "       waitset_bench sub read|read0|waitset PREFIX N TOPIC COUNT WARMUP OUT\n"
    "           TOPIC and N - 1 silent topics PREFIX.<i> (waitset: all attached); one-way\n"
    "           latency (ns) of the samples after WARMUP to OUT\n"
    "       waitset_bench idle waitset|sleep PREFIX N SECONDS\n"
    "           N silent topics and a 1 s timer in a waitset (or a plain sleep) for SECONDS\n"
    "Each prints one JSON line at the end; sub and idle say \"ready\" once set up.\n";

#define STAMP_OFFSET 8 /* the publisher's CLOCK_MONOTONIC (ns) after the counter */
#define EVENTS 16
#define BUFFERS 16 /* the timed subscriber is queued: a late read is timed, not skipped */

typedef struct sample {
    uint64_t counter;
    uint64_t stamp_ns;
    uint8_t rest[64 - 16];
} sample;
/* py_waitset.py reads the stamp at this offset */
_Static_assert(offsetof(sample, stamp_ns) == STAMP_OFFSET, "stamp offset");

static void sleep_until(uint64_t ns)
{
    struct timespec ts = {(time_t)(ns / 1000000000u), (long)(ns % 1000000000u)};
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, NULL) == EINTR) {
    }
}

static ln_client* open_client(const char* name)
{
    ln_client* clnt;
    int rc = ln_client_create(&clnt, name, NULL);
    if (rc < 0)
        bench_fail("ln_client_create", rc);
    return clnt;
}

static ln_inport* subscribe(ln_client* clnt, const char* topic, uint32_t buffers, uint32_t spin_us)
{
    bench_md md = bench_md_for(sizeof(sample));
    ln_port_options opts;
    ln_port_options_init(&opts);
    opts.buffers = buffers;
    opts.spin_us = spin_us;
    ln_inport* port;
    int rc = ln_subscribe(clnt, &port, topic, md.name, md.hash, md.size, &opts);
    if (rc < 0)
        bench_fail(topic, rc);
    return port;
}

/* `count` silent topics PREFIX.<i>, attached to `ws` when it is not NULL. */
static void silent_topics(ln_client* clnt, ln_waitset* ws, const char* prefix, long count)
{
    for (long i = 0; i < count; i++) {
        char topic[256];
        snprintf(topic, sizeof topic, "%s.%ld", prefix, i);
        ln_inport* port = subscribe(clnt, topic, 1, LN_DEFAULT_SPIN_US);
        int rc = ws ? ln_waitset_attach_inport(ws, port, LN_WAIT_ON_DATA, 0, NULL, NULL) : 0;
        if (rc < 0)
            bench_fail("ln_waitset_attach_inport", rc);
    }
}

static int by_value(const void* a, const void* b)
{
    uint64_t x = *(const uint64_t*)a, y = *(const uint64_t*)b;
    return (x > y) - (x < y);
}

/* The publisher's half of the latency: how long ln_write took (it wakes the reader). */
static int publish(const char* topic, uint64_t count, uint64_t period_us)
{
    ln_client* clnt = open_client("waitset_bench_pub");
    bench_md md = bench_md_for(sizeof(sample));
    ln_outport* pub;
    int rc = ln_publish(clnt, &pub, topic, md.name, md.hash, md.size, NULL);
    if (rc < 0)
        bench_fail("ln_publish", rc);
    for (int tries = 0; ln_outport_subscriber_count(pub) < 1; tries++) {
        if (tries == 10000) {
            fprintf(stderr, "waitset_bench: no subscriber of %s within 10 s\n", topic);
            return 2;
        }
        sleep_until(bench_now_ns() + 1000000u);
    }
    sample s;
    memset(&s, 0x5a, sizeof s);
    uint64_t* took_ns = bench_alloc((count ? count : 1) * sizeof(uint64_t));
    uint64_t next = bench_now_ns(), late = 0;
    for (uint64_t i = 0; i < count; i++) {
        next += period_us * 1000u;
        sleep_until(next);
        s.counter = i;
        s.stamp_ns = bench_now_ns();
        late += s.stamp_ns > next + period_us * 1000u; /* a whole period late */
        if ((rc = ln_write(pub, &s, sizeof s, -1)) < 0)
            bench_fail("ln_write", rc);
        took_ns[i] = bench_now_ns() - s.stamp_ns;
    }
    qsort(took_ns, count, sizeof *took_ns, by_value);
    printf("{\"sent\": %" PRIu64 ", \"late\": %" PRIu64 ", \"write_p50_ns\": %" PRIu64 "}\n", count,
           late, count ? took_ns[count / 2] : 0);
    ln_client_destroy(clnt);
    return 0;
}

/* What a subscriber measured: latencies after the warm-up, its CPU time over them. */
typedef struct receipts {
    uint64_t *lat, count, warmup, got, waits;
    uint64_t next; /* the counter expected next */
    uint64_t lost;
    double cpu0, t0;
} receipts;

/* One sample read at `now`; 1 once the last one came. */
static int took(receipts* r, const sample* s, uint64_t now)
{
    if (s->counter >= r->warmup && r->got == 0) { /* CPU and waits from here on */
        r->cpu0 = bench_cpu_s();
        r->t0 = (double)now * 1e-9;
        r->waits = 0;
    }
    if (s->counter >= r->next)
        r->lost += s->counter - r->next;
    r->next = s->counter + 1;
    if (s->counter >= r->warmup && r->got < r->count)
        r->lat[r->got++] = now - s->stamp_ns;
    return s->counter + 1 >= r->warmup + r->count;
}

static void read_loop(ln_inport* port, receipts* r)
{
    sample s;
    for (;;) {
        int rc = ln_read(port, &s, sizeof s, 10.0, NULL);
        if (rc < 0)
            bench_fail("ln_read", rc);
        r->waits++;
        if (took(r, &s, bench_now_ns()))
            return;
    }
}

static void waitset_loop(ln_waitset* ws, ln_inport* port, uint32_t active, receipts* r)
{
    ln_waitset_event ev[EVENTS];
    sample s;
    for (;;) {
        int n = ln_waitset_wait(ws, 10.0, ev, EVENTS);
        if (n == 0) {
            fprintf(stderr, "waitset_bench: no sample within 10 s\n");
            exit(2);
        }
        if (n == LN_EINTR)
            continue;
        if (n < 0)
            bench_fail("ln_waitset_wait", n);
        r->waits++;
        for (int i = 0; i < n; i++) {
            if (ev[i].id != active || ev[i].kind != LN_WAIT_DATA) {
                fprintf(stderr, "waitset_bench: unexpected event %u of %u\n", ev[i].kind, ev[i].id);
                exit(2);
            }
            int rc;
            while ((rc = ln_read(port, &s, sizeof s, 0, NULL)) == LN_OK)
                if (took(r, &s, bench_now_ns()))
                    return;
            if (rc != LN_EAGAIN)
                bench_fail("ln_read", rc);
        }
    }
}

static int subscribe_and_time(char** argv)
{
    const char* mode = argv[2];
    int use_ws = strcmp(mode, "waitset") == 0;
    if (!use_ws && strcmp(mode, "read") != 0 && strcmp(mode, "read0") != 0) {
        fputs(usage, stderr);
        return 2;
    }
    long n = strtol(argv[4], NULL, 10);
    receipts r = {.count = strtoull(argv[6], NULL, 10), .warmup = strtoull(argv[7], NULL, 10)};
    if (n < 1 || r.count < 1) {
        fputs(usage, stderr);
        return 2;
    }
    r.lat = bench_alloc(r.count * sizeof(uint64_t));
    ln_client* clnt = open_client("waitset_bench_sub");
    ln_waitset* ws = NULL;
    int rc;
    if (use_ws && (rc = ln_waitset_create(&ws)) < 0)
        bench_fail("ln_waitset_create", rc);
    uint64_t t_setup = bench_now_ns();
    silent_topics(clnt, ws, argv[3], n - 1);
    ln_inport* port =
        subscribe(clnt, argv[5], BUFFERS, strcmp(mode, "read0") == 0 ? 0 : LN_DEFAULT_SPIN_US);
    uint32_t active = 0;
    if (ws && (rc = ln_waitset_attach_inport(ws, port, LN_WAIT_ON_DATA, 0, NULL, &active)) < 0)
        bench_fail("ln_waitset_attach_inport", rc);
    double setup_s = (double)(bench_now_ns() - t_setup) * 1e-9;
    bench_ready();
    if (ws)
        waitset_loop(ws, port, active, &r);
    else
        read_loop(port, &r);
    double cpu = bench_cpu_s() - r.cpu0, wall = (double)bench_now_ns() * 1e-9 - r.t0;
    printf("{\"samples\": %" PRIu64 ", \"lost\": %" PRIu64 ", \"waits\": %" PRIu64
           ", \"cpu_s\": %.6f, \"wall_s\": %.6f, \"setup_s\": %.6f, \"inports\": %ld}\n",
           r.got, r.lost, r.waits, cpu, wall, setup_s, n);
    fflush(stdout);
    bench_write_samples(argv[8], r.lat, r.got);
    if (ws)
        ln_waitset_destroy(ws);
    ln_client_destroy(clnt);
    return 0;
}

/* N silent topics and a 1 s timer in a waitset, or only a sleep, for `seconds`. */
static int idle(const char* mode, const char* prefix, long n, double seconds)
{
    int use_ws = strcmp(mode, "waitset") == 0;
    if ((!use_ws && strcmp(mode, "sleep") != 0) || n < 0 || !(seconds > 0)) {
        fputs(usage, stderr);
        return 2;
    }
    ln_client* clnt = open_client("waitset_bench_idle");
    ln_waitset* ws = NULL;
    int rc;
    if (use_ws && (rc = ln_waitset_create(&ws)) < 0)
        bench_fail("ln_waitset_create", rc);
    silent_topics(clnt, ws, prefix, n);
    if (ws && (rc = ln_waitset_attach_timer(ws, 0, 1.0, NULL, NULL)) < 0)
        bench_fail("ln_waitset_attach_timer", rc);
    bench_ready();
    uint64_t t0 = bench_now_ns(), end = t0 + (uint64_t)(seconds * 1e9);
    double cpu0 = bench_cpu_s();
    uint64_t wakeups = 0, timers = 0, others = 0;
    if (!ws)
        sleep_until(end);
    for (uint64_t now = t0; ws && now < end; now = bench_now_ns()) {
        ln_waitset_event ev[EVENTS];
        int got = ln_waitset_wait(ws, (double)(end - now) * 1e-9, ev, EVENTS);
        if (got < 0 && got != LN_EINTR)
            bench_fail("ln_waitset_wait", got);
        wakeups++;
        for (int i = 0; i < got; i++) {
            timers += ev[i].kind == LN_WAIT_TIMER ? ev[i].count : 0;
            others += ev[i].kind != LN_WAIT_TIMER;
        }
    }
    double cpu = bench_cpu_s() - cpu0, wall = (double)(bench_now_ns() - t0) * 1e-9;
    printf("{\"cpu_s\": %.6f, \"wall_s\": %.6f, \"wakeups\": %" PRIu64
           ", \"timer_expiries\": %" PRIu64 ", \"other_events\": %" PRIu64 ", \"inports\": %ld}\n",
           cpu, wall, wakeups, timers, others, n);
    if (ws)
        ln_waitset_destroy(ws);
    ln_client_destroy(clnt);
    return 0;
}

int main(int argc, char** argv)
{
    if (argc == 5 && strcmp(argv[1], "pub") == 0)
        return publish(argv[2], strtoull(argv[3], NULL, 10), strtoull(argv[4], NULL, 10));
    if (argc == 9 && strcmp(argv[1], "sub") == 0)
        return subscribe_and_time(argv);
    if (argc == 6 && strcmp(argv[1], "idle") == 0)
        return idle(argv[2], argv[3], strtol(argv[4], NULL, 10), strtod(argv[5], NULL));
    fputs(usage, stderr);
    return 2;
}
