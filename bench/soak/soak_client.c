/* soak_client.c — the processes of the soak benchmark (bench/soak/bench_soak.py), one program
 * with a role per process: publishers of many topics at a fixed rate on absolute deadlines,
 * subscribers that time publish -> receive, light subscribers, echo providers and callers.
 * Started by ln_manager (manager from $LN_MANAGER); run until SIGTERM. */
#define _GNU_SOURCE 1
#include <errno.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <ln/ln.h>

#include "bench_messages.h"
#include "bench_services.h"

static const char usage[] =
    "usage: soak_client pub PREFIX FIRST COUNT RATE          COUNT topics PREFIX.N at RATE Hz\n"
    "       soak_client sub OUT WINDOW PREFIX FIRST COUNT    time every sample, stats to OUT\n"
    "       soak_client light PREFIX N PERIOD_MS              read PREFIX.N every PERIOD_MS\n"
    "       soak_client provide SERVICE                      answer echo calls\n"
    "       soak_client call OUT WINDOW SERVICE RATE         RATE calls/s, stats to OUT\n"
    "OUT gets one JSON line per WINDOW seconds: latency percentiles in microseconds.\n";

#define BINS 200000u /* 1 us bins up to 200 ms; later values count in the last one */

static volatile sig_atomic_t stop;

static void on_term(int sig)
{
    (void)sig;
    stop = 1;
}

static void fail(const char* what, int rc)
{
    fprintf(stderr, "soak_client: %s: %s: %s\n", what, ln_error_name(rc), ln_last_error());
    exit(2);
}

static int64_t now_ns(clockid_t clock)
{
    struct timespec ts;
    clock_gettime(clock, &ts);
    return (int64_t)ts.tv_sec * 1000000000 + ts.tv_nsec;
}

static void sleep_until(int64_t deadline_ns)
{
    struct timespec ts = {(time_t)(deadline_ns / 1000000000), (long)(deadline_ns % 1000000000)};
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, NULL) == EINTR && !stop) {
    }
}

/* Latencies of one window as a histogram, written as a JSON line when the window ends.
 * Windows end at multiples of their length in CLOCK_REALTIME, so that the windows of all
 * processes cover the same time (the first one is shorter). */
typedef struct window {
    FILE* out;
    double seconds;
    int64_t start, end_rt;
    uint32_t* bins;
    uint64_t n, errors, lost;
    double max_us;
} window;

static void window_open(window* w, const char* path, const char* seconds)
{
    w->out = fopen(path, "a");
    w->bins = calloc(BINS, sizeof *w->bins);
    w->seconds = atof(seconds);
    if (!w->out || !w->bins || !(w->seconds > 0)) {
        perror(path);
        exit(2);
    }
    w->start = now_ns(CLOCK_MONOTONIC);
    int64_t length = (int64_t)(w->seconds * 1e9);
    w->end_rt = (now_ns(CLOCK_REALTIME) / length + 1) * length;
}

static void window_add(window* w, int64_t ns)
{
    uint64_t us = ns < 0 ? 0 : (uint64_t)ns / 1000;
    w->bins[us < BINS ? us : BINS - 1]++;
    w->n++;
    if (ns / 1e3 > w->max_us)
        w->max_us = ns / 1e3;
}

static double window_pct(const window* w, double q)
{
    uint64_t rank = (uint64_t)(q * (double)w->n), seen = 0;
    for (uint32_t i = 0; i < BINS; i++) {
        seen += w->bins[i];
        if (seen > rank)
            return i + 0.5;
    }
    return BINS;
}

/* Ends the window when its time is up (or `force`): one line to OUT, counters reset. */
static void window_tick(window* w, int force)
{
    int64_t now = now_ns(CLOCK_MONOTONIC), now_rt = now_ns(CLOCK_REALTIME);
    if (!force && now_rt < w->end_rt)
        return;
    int64_t length = (int64_t)(w->seconds * 1e9);
    w->end_rt = (now_rt / length + 1) * length;
    fprintf(w->out,
            "{\"t\": %.3f, \"seconds\": %.3f, \"n\": %llu, \"errors\": %llu, \"lost\": %llu, "
            "\"p50_us\": %.1f, \"p99_us\": %.1f, \"p999_us\": %.1f, \"max_us\": %.1f}\n",
            now_rt / 1e9, (now - w->start) / 1e9, (unsigned long long)w->n,
            (unsigned long long)w->errors, (unsigned long long)w->lost, window_pct(w, 0.5),
            window_pct(w, 0.99), window_pct(w, 0.999), w->max_us);
    fflush(w->out);
    memset(w->bins, 0, BINS * sizeof *w->bins);
    w->n = w->errors = w->lost = 0;
    w->max_us = 0;
    w->start = now;
}

static ln_client* connect_client(const char* name)
{
    ln_client* clnt;
    int rc = ln_client_create(&clnt, name, NULL);
    if (rc < 0)
        fail("ln_client_create", rc);
    return clnt;
}

static void topic_name(char* out, size_t size, const char* prefix, long n)
{
    snprintf(out, size, "%s.%ld", prefix, n);
}

static int publisher(const char* prefix, long first, long count, double rate)
{
    ln_client* clnt = connect_client("soak_pub");
    ln_outport** ports = calloc((size_t)count, sizeof *ports);
    char topic[128];
    for (long i = 0; i < count; i++) {
        topic_name(topic, sizeof topic, prefix, first + i);
        int rc = ln_publish(clnt, &ports[i], topic, LNBENCH_SAMPLE_64_MD_NAME,
                            LNBENCH_SAMPLE_64_LAYOUT_HASH, sizeof(lnbench_sample_64_t), NULL);
        if (rc < 0)
            fail("ln_publish", rc);
    }
    printf("ready\n");
    fflush(stdout);
    int64_t period = (int64_t)(1e9 / rate), next = now_ns(CLOCK_MONOTONIC);
    uint64_t counter = 0, late = 0;
    lnbench_sample_64_t sample;
    memset(&sample, 0, sizeof sample);
    while (!stop) {
        next += period;
        sleep_until(next);
        if (now_ns(CLOCK_MONOTONIC) > next + period) {
            late++; /* a whole period behind: skip ahead instead of bursting to catch up */
            next = now_ns(CLOCK_MONOTONIC);
        }
        sample.counter = ++counter;
        for (long i = 0; i < count; i++) {
            int rc = ln_write(ports[i], &sample, sizeof sample, 0);
            if (rc < 0)
                fail("ln_write", rc);
        }
    }
    fprintf(stderr, "soak_client pub: %llu cycles, %llu late\n", (unsigned long long)counter,
            (unsigned long long)late);
    free(ports);
    ln_client_destroy(clnt);
    return 0;
}

/* Blocks on the last topic (its publisher writes it last in each cycle), then takes what the
 * others have: every sample is timed from its publish stamp to when it was read. */
static int subscriber(const char* out, const char* seconds, const char* prefix, long first,
                      long count)
{
    ln_client* clnt = connect_client("soak_sub");
    ln_inport** ports = calloc((size_t)count, sizeof *ports);
    ln_port_options opts;
    ln_port_options_init(&opts);
    opts.buffers = 16;
    char topic[128];
    for (long i = 0; i < count; i++) {
        topic_name(topic, sizeof topic, prefix, first + i);
        int rc = ln_subscribe(clnt, &ports[i], topic, LNBENCH_SAMPLE_64_MD_NAME,
                              LNBENCH_SAMPLE_64_LAYOUT_HASH, sizeof(lnbench_sample_64_t), &opts);
        if (rc < 0)
            fail("ln_subscribe", rc);
    }
    window w;
    window_open(&w, out, seconds);
    printf("ready\n");
    fflush(stdout);
    lnbench_sample_64_t sample;
    ln_sample_info info;
    while (!stop) {
        for (long k = count - 1; k >= 0; k--) {
            double timeout = k == count - 1 ? 0.1 : 0;
            int rc;
            while ((rc = ln_read(ports[k], &sample, sizeof sample, timeout, &info)) == LN_OK) {
                window_add(&w, now_ns(CLOCK_REALTIME) - info.timestamp_ns);
                w.lost += info.overruns;
                timeout = 0;
            }
            if (rc != LN_EAGAIN && rc != LN_ETIMEOUT)
                w.errors++;
        }
        window_tick(&w, 0);
    }
    window_tick(&w, 1);
    free(ports);
    ln_client_destroy(clnt);
    return 0;
}

static int light(const char* prefix, long n, long period_ms)
{
    ln_client* clnt = connect_client("soak_light");
    ln_inport* port;
    char topic[128];
    topic_name(topic, sizeof topic, prefix, n);
    int rc = ln_subscribe(clnt, &port, topic, LNBENCH_SAMPLE_64_MD_NAME,
                          LNBENCH_SAMPLE_64_LAYOUT_HASH, sizeof(lnbench_sample_64_t), NULL);
    if (rc < 0)
        fail("ln_subscribe", rc);
    printf("ready\n");
    fflush(stdout);
    lnbench_sample_64_t sample;
    int64_t next = now_ns(CLOCK_MONOTONIC);
    while (!stop) {
        next += period_ms * 1000000;
        sleep_until(next);
        rc = ln_read(port, &sample, sizeof sample, 0, NULL);
        if (rc < 0 && rc != LN_EAGAIN)
            fail("ln_read", rc);
    }
    ln_client_destroy(clnt);
    return 0;
}

static int echo(ln_client* clnt, ln_service_request* req, void* user_data)
{
    (void)clnt;
    (void)user_data;
    bench_echo64_request_t in;
    bench_echo64_response_t resp;
    int rc = ln_service_request_get_data(req, &in);
    if (rc < 0)
        return rc;
    memcpy(resp.data, in.data, sizeof resp.data);
    return ln_service_request_respond(req, &resp);
}

static int provider(const char* name)
{
    ln_client* clnt = connect_client("soak_provider");
    ln_service_provider* prov;
    int rc = ln_get_service_provider(clnt, &prov, name, BENCH_ECHO64_SERVICE);
    if (rc < 0 || (rc = ln_service_provider_set_handler(prov, echo, NULL)) < 0 ||
        (rc = ln_service_provider_register(prov, NULL)) < 0)
        fail("service provider", rc);
    printf("ready\n");
    fflush(stdout);
    while (!stop)
        if ((rc = ln_wait_and_handle_service_group_requests(clnt, NULL, 0.2)) < 0)
            fail("ln_wait_and_handle_service_group_requests", rc);
    ln_unregister_service_provider(prov);
    ln_client_destroy(clnt);
    return 0;
}

static int caller(const char* out, const char* seconds, const char* name, double rate)
{
    ln_client* clnt = connect_client("soak_caller");
    ln_service* svc;
    int rc = ln_get_service(clnt, &svc, name, BENCH_ECHO64_SERVICE);
    if (rc < 0)
        fail("ln_get_service", rc);
    window w;
    window_open(&w, out, seconds);
    printf("ready\n");
    fflush(stdout);
    bench_echo64_request_t req;
    bench_echo64_response_t resp;
    memset(&req, 0, sizeof req);
    int64_t period = (int64_t)(1e9 / rate), next = now_ns(CLOCK_MONOTONIC);
    uint64_t number = 0;
    while (!stop) {
        next += period;
        sleep_until(next);
        if (now_ns(CLOCK_MONOTONIC) > next + period)
            next = now_ns(CLOCK_MONOTONIC);
        number++;
        memcpy(req.data, &number, sizeof number);
        int64_t t0 = now_ns(CLOCK_MONOTONIC);
        rc = ln_service_call(svc, &req, &resp, 2.0);
        if (rc == LN_OK && memcmp(resp.data, &number, sizeof number) == 0)
            window_add(&w, now_ns(CLOCK_MONOTONIC) - t0);
        else
            w.errors++;
        window_tick(&w, 0);
    }
    window_tick(&w, 1);
    ln_service_release(svc);
    ln_client_destroy(clnt);
    return 0;
}

int main(int argc, char** argv)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_term;
    sigaction(SIGTERM, &sa, NULL);
    sigaction(SIGINT, &sa, NULL);
    const char* role = argc > 1 ? argv[1] : "";
    if (!strcmp(role, "pub") && argc == 6)
        return publisher(argv[2], atol(argv[3]), atol(argv[4]), atof(argv[5]));
    if (!strcmp(role, "sub") && argc == 7)
        return subscriber(argv[2], argv[3], argv[4], atol(argv[5]), atol(argv[6]));
    if (!strcmp(role, "light") && argc == 5)
        return light(argv[2], atol(argv[3]), atol(argv[4]));
    if (!strcmp(role, "provide") && argc == 3)
        return provider(argv[2]);
    if (!strcmp(role, "call") && argc == 6)
        return caller(argv[2], argv[3], argv[4], atof(argv[5]));
    fputs(usage, stderr);
    return 2;
}
