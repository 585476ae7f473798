/* iox_bench.c — the iceoryx (1.x/2.0 C binding) peer of lat_ln zc|full and thr_ln zc|full:
 * loan a chunk, write its first and last 8 bytes (zc) or copy a whole source buffer into it
 * (full), publish; take, read them or copy the whole chunk out (the echo: into its own loan),
 * release.  Needs a running iox-roudi with mempools for the size; built only where the
 * iceoryx headers are installed. */
#include <inttypes.h>
#include <sched.h>
#include <stdbool.h>
#include <time.h>
#include <unistd.h>

#include "iceoryx_binding_c/chunk.h"
#include "iceoryx_binding_c/log.h"
#include "iceoryx_binding_c/publisher.h"
#include "iceoryx_binding_c/runtime.h"
#include "iceoryx_binding_c/subscriber.h"
#include "iceoryx_binding_c/wait_set.h"

#include "bench_common.h"
#include "iox_take.h"

static const char usage[] =
    "usage: iox_bench pong NAME SIZE TOTAL WARMUP SPIN_US [zc|full]\n"
    "       iox_bench ping NAME SIZE COUNT WARMUP OUT SPIN_US [zc|full]   COUNT round trips\n"
    "       iox_bench sub NAME SIZE COUNT BUFFERS WARM SPIN_US [zc|full]  until the last or 2 s\n"
    "       iox_bench pub NAME SIZE COUNT WARM SECONDS [zc|full]          waits for the queue\n"
    "zc (default): the first and last 8 bytes of a chunk; full: the whole payload copied in\n"
    "and out.  Waiting for a chunk spins (sched_yield) SPIN_US, as libln's spin_us, then\n"
    "sleeps in a WaitSet.  Each prints a JSON line with its minor faults from sample WARM(UP)\n"
    "on; ping writes its round trips (ns) to OUT.\n";

typedef struct port {
    iox_pub_storage_t pub_storage;
    iox_sub_storage_t sub_storage;
    iox_ws_storage_t ws_storage;
    iox_pub_t pub;
    iox_sub_t sub;
    iox_ws_t ws;
    size_t size;
    uint64_t spin_ns;
    int full;      /* the whole payload is copied into loans and out of chunks */
    uint8_t* src;  /* full: what a sample is copied from (stamped) */
    uint8_t* copy; /* full: where a received sample is copied to */
} port;

static void open_pub(port* p, const char* name, const char* event, bool block)
{
    iox_pub_options_t o;
    iox_pub_options_init(&o);
    o.historyCapacity = 0;
    o.subscriberTooSlowPolicy =
        block ? ConsumerTooSlowPolicy_WAIT_FOR_CONSUMER : ConsumerTooSlowPolicy_DISCARD_OLDEST_DATA;
    p->pub = iox_pub_init(&p->pub_storage, "lnbench", name, event, &o);
}

static void open_sub(port* p, const char* name, const char* event, uint64_t queue, bool block)
{
    iox_sub_options_t o;
    iox_sub_options_init(&o);
    o.queueCapacity = queue;
    o.historyRequest = 0;
    o.queueFullPolicy =
        block ? QueueFullPolicy_BLOCK_PRODUCER : QueueFullPolicy_DISCARD_OLDEST_DATA;
    p->sub = iox_sub_init(&p->sub_storage, "lnbench", name, event, &o);
    p->ws = iox_ws_init(&p->ws_storage);
    if (iox_ws_attach_subscriber_state(p->ws, p->sub, SubscriberState_HAS_DATA, 0, NULL) !=
        WaitSetResult_SUCCESS) {
        fputs("iox_bench: cannot attach the subscriber to a WaitSet\n", stderr);
        exit(2);
    }
}

/* Until the subscription is up (RouDi connects ports in its discovery loop). */
static void wait_subscribed(const port* p)
{
    while (iox_sub_get_subscription_state(p->sub) != SubscribeState_SUBSCRIBED)
        nanosleep(&(struct timespec){0, 1000000}, NULL);
}

static void wait_subscribers(const port* p)
{
    while (!iox_pub_has_subscribers(p->pub))
        nanosleep(&(struct timespec){0, 1000000}, NULL);
}

static void* loan(const port* p)
{
    void* chunk;
    enum iox_AllocationResult rc = iox_pub_loan_chunk(p->pub, &chunk, (uint32_t)p->size);
    if (rc != AllocationResult_SUCCESS) {
        fprintf(stderr,
                "iox_bench: iox_pub_loan_chunk of %zu bytes failed (%d); does RouDi's "
                "config have a mempool for it?\n",
                p->size, (int)rc);
        exit(2);
    }
    return chunk;
}

static void send_one(const port* p, uint64_t value)
{
    void* chunk = loan(p);
    if (p->full) {
        bench_stamp(p->src, p->size, value);
        memcpy(chunk, p->src, p->size);
    } else {
        bench_stamp(chunk, p->size, value);
    }
    iox_pub_publish_chunk(p->pub, chunk);
}

/* The next chunk, not yet released; NULL after `timeout_s` without one. */
static const void* take(const port* p, double timeout_s)
{
    return iox_take_chunk(p->sub, p->ws, p->spin_ns, timeout_s, "iox_bench");
}

/* The next sample's value (its chunk released; full: copied out whole first); 0 in *got
 * after `timeout_s` without one. */
static uint64_t receive_one(const port* p, double timeout_s, int* got)
{
    const void* chunk = take(p, timeout_s);
    *got = chunk != NULL;
    if (!chunk)
        return 0;
    if (!p->full) {
        uint64_t value = bench_check(chunk, p->size, "iox_bench");
        iox_sub_release_chunk(p->sub, chunk);
        return value;
    }
    memcpy(p->copy, chunk, p->size);
    iox_sub_release_chunk(p->sub, chunk);
    return bench_check(p->copy, p->size, "iox_bench");
}

/* The echo: the next sample back (full: copied whole into a loan); 0 after 60 s without one. */
static int echo_one(const port* p)
{
    int got;
    if (!p->full) {
        uint64_t value = receive_one(p, 60.0, &got);
        if (got)
            send_one(p, value);
        return got;
    }
    const void* chunk = take(p, 60.0);
    if (!chunk)
        return 0;
    void* out = loan(p);
    memcpy(out, chunk, p->size);
    iox_sub_release_chunk(p->sub, chunk);
    bench_check(out, p->size, "iox_bench");
    iox_pub_publish_chunk(p->pub, out);
    return 1;
}

static void print_faults(uint64_t since, uint64_t samples)
{
    printf("{\"minflt\": %" PRIu64 ", \"samples\": %" PRIu64 "}\n", bench_minflt() - since,
           samples);
}

static int pingpong(int ping, char** argv, port* p)
{
    char event[64];
    snprintf(event, sizeof event, "%s.%s", argv[2], ping ? "ping" : "pong");
    open_pub(p, "lat", event, false);
    snprintf(event, sizeof event, "%s.%s", argv[2], ping ? "pong" : "ping");
    open_sub(p, "lat", event, 4, false);
    uint64_t count = strtoull(argv[4], NULL, 10), warmup = strtoull(argv[5], NULL, 10);
    uint64_t faults = 0;
    int got;
    if (!ping) {
        bench_ready();
        for (uint64_t i = 0; i < count; i++) {
            if (i == warmup)
                faults = bench_minflt();
            if (!echo_one(p))
                return 1;
        }
        print_faults(faults, count > warmup ? count - warmup : 0);
        return 0;
    }
    wait_subscribed(p);
    wait_subscribers(p);
    uint64_t* rtt =
        bench_alloc((count ? count : 1) * sizeof(uint64_t)); /* touched: no faults later */
    for (uint64_t i = 0; rtt && i < warmup + count; i++) {
        if (i == warmup)
            faults = bench_minflt();
        uint64_t t0 = bench_now_ns();
        send_one(p, i);
        uint64_t back = receive_one(p, 60.0, &got);
        uint64_t t1 = bench_now_ns();
        if (!got || back != i) {
            fprintf(stderr, "iox_bench: round trip %" PRIu64 " came back wrong\n", i);
            return 1;
        }
        if (i >= warmup)
            rtt[i - warmup] = t1 - t0;
    }
    print_faults(faults, count);
    bench_write_samples(argv[6], rtt, count);
    return 0;
}

static int subscriber(char** argv, port* p)
{
    uint64_t count = strtoull(argv[4], NULL, 10), warm = strtoull(argv[6], NULL, 10);
    open_sub(p, "thr", argv[2], strtoull(argv[5], NULL, 10), true);
    bench_ready();
    uint64_t received = 0, last = 0, disorder = 0, first_ns = 0, last_ns = 0, faults = 0;
    uint64_t counted = 0;
    int got;
    while (received == 0 || last + 1 < count) {
        uint64_t value = receive_one(p, received ? 2.0 : 60.0, &got);
        if (!got)
            break;
        last_ns = bench_now_ns();
        if (!counted && value >= warm)
            faults = bench_minflt();
        counted += counted || value >= warm;
        if (received++ == 0)
            first_ns = last_ns;
        else if (value <= last)
            disorder++;
        last = value;
    }
    printf("{\"received\": %" PRIu64 ", \"overruns\": 0, \"disorder\": %" PRIu64
           ", \"elapsed_s\": %.9f, \"minflt\": %" PRIu64 ", \"fault_samples\": %" PRIu64 "}\n",
           received, disorder, (double)(last_ns - first_ns) * 1e-9,
           counted ? bench_minflt() - faults : 0, counted);
    return 0;
}

static int publisher(char** argv, port* p)
{
    uint64_t count = strtoull(argv[4], NULL, 10), warm = strtoull(argv[5], NULL, 10);
    double seconds = atof(argv[6]);
    open_pub(p, "thr", argv[2], true);
    wait_subscribers(p);
    bench_ready();
    uint64_t t0 = bench_now_ns(), faults = bench_minflt(), sent = 0;
    uint64_t stop_ns = seconds > 0 ? t0 + (uint64_t)(seconds * 1e9) : UINT64_MAX;
    for (uint64_t i = 0; i < count; i++) {
        if (i == warm)
            faults = bench_minflt();
        int last = (i & 15) == 0 && bench_now_ns() > stop_ns;
        send_one(p, last ? count - 1 : i);
        sent++;
        if (last)
            break;
    }
    uint64_t t1 = bench_now_ns();
    printf("{\"sent\": %" PRIu64 ", \"elapsed_s\": %.9f, \"minflt\": %" PRIu64
           ", \"fault_samples\": %" PRIu64 "}\n",
           sent, (double)(t1 - t0) * 1e-9, sent > warm ? bench_minflt() - faults : 0,
           sent > warm ? sent - warm : 0);
    return 0;
}

int main(int argc, char** argv)
{
    static const struct {
        const char* role;
        int argc;
    } roles[] = {{"pong", 7}, {"ping", 8}, {"sub", 8}, {"pub", 7}};
    /* an optional payload mode after the role's arguments */
    int full = argc > 1 && strcmp(argv[argc - 1], "full") == 0;
    if (full || (argc > 1 && strcmp(argv[argc - 1], "zc") == 0))
        argc--;
    int role = -1;
    for (int i = 0; i < 4; i++)
        if (argc == roles[i].argc && strcmp(argv[1], roles[i].role) == 0)
            role = i;
    if (role < 0) {
        fputs(usage, stderr);
        return 2;
    }
    static port p; /* the storages are large */
    p.full = full;
    p.size = strtoull(argv[3], NULL, 10);
    p.spin_ns = role == 3 ? 0 : strtoull(argv[argc - 1], NULL, 10) * 1000u;
    if (p.size < 16) {
        fputs("iox_bench: SIZE must be at least 16\n", stderr);
        return 2;
    }
    if (p.full) { /* touched before timing */
        p.src = bench_alloc(p.size);
        p.copy = bench_alloc(p.size);
    }
    char name[64];
    snprintf(name, sizeof name, "iox_bench_%s_%d", roles[role].role, (int)getpid());
    iox_set_loglevel(Iceoryx_LogLevel_Warn); /* stdout is for the driver */
    iox_runtime_init(name);
    int rc = role <= 1   ? pingpong(role == 1, argv, &p)
             : role == 2 ? subscriber(argv, &p)
                         : publisher(argv, &p);
    fflush(stdout);
    if (p.sub) {
        iox_ws_deinit(p.ws);
        iox_sub_deinit(p.sub);
    }
    if (p.pub)
        iox_pub_deinit(p.pub);
    iox_runtime_shutdown();
    return rc;
}
