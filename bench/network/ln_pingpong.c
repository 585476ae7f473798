/* ln_pingpong.c — topics between hosts: ping-pong latency through PREFIX.ping/PREFIX.pong and
 * the throughput of a stream on PREFIX.data, the subscriptions asking for UDP or TCP
 * transport (LN_SUBSCRIBE_*).  The same programs run with both sides on one host, where the
 * samples never leave shared memory.  Manager from $LN_MANAGER. */
#include <inttypes.h>
#include <signal.h>

#include "bench_common.h"

static const char usage[] =
    "usage: ln_pingpong pong PREFIX SIZE MODE                   echo PREFIX.ping on PREFIX.pong "
    "until SIGTERM\n"
    "       ln_pingpong ping PREFIX SIZE MODE COUNT WARMUP OUT  COUNT round trips (ns) to OUT\n"
    "       ln_pingpong sink PREFIX SIZE MODE COUNT             count samples of PREFIX.data\n"
    "       ln_pingpong source PREFIX SIZE MODE COUNT RATE      publish COUNT samples on "
    "PREFIX.data,\n"
    "                                                           RATE per second (0: no pause)\n"
    "MODE: udp | tcp | default (LN_SUBSCRIBE_UDP, LN_SUBSCRIBE_TCP or neither) for every\n"
    "subscription.  SIZE: 64, 4096, 65536, 1048576, 4194304, 16777216 or 67108864 (the\n"
    "lnbench/sample_* mds).  pong and sink print \"ready\" once subscribed; ping, sink and\n"
    "source print one JSON line (sink and source with cpu_s, their CPU seconds, user + system,\n"
    "the client's threads included).\n";

#define RETRY_S 1.0        /* ping: resend a ping not answered within this */
#define GIVE_UP_S 60.0     /* nothing at all arrived for this long: the topic is not forwarded */
#define IDLE_S 2.0         /* sink: the stream has ended when nothing came for this long */
#define PRIME (1ull << 63) /* source: marks the samples sent until the sink answers */
#define DONE UINT64_MAX    /* sink -> source on PREFIX.ready: counting has ended */
#define SINK_MEMORY ((size_t)64 << 20) /* bytes of the sink's queue */

static volatile sig_atomic_t stop;

static void on_signal(int sig)
{
    (void)sig;
    stop = 1;
}

static uint32_t transport_flags(const char* mode)
{
    if (strcmp(mode, "udp") == 0)
        return LN_SUBSCRIBE_UDP;
    if (strcmp(mode, "tcp") == 0)
        return LN_SUBSCRIBE_TCP;
    if (strcmp(mode, "default") == 0)
        return 0;
    fprintf(stderr, "ln_pingpong: MODE must be udp, tcp or default, not %s\n", mode);
    exit(2);
}

typedef struct ends {
    ln_client* clnt;
    ln_outport* pub;
    ln_inport* sub;
} ends;

/* Publish PREFIX.<out> with `out_md` and subscribe PREFIX.<in> with `in_md`. */
static ends open_ends(const char* role, const char* prefix, const char* out, bench_md out_md,
                      const char* in, bench_md in_md, uint32_t flags, uint32_t buffers)
{
    char client[64], out_topic[256], in_topic[256];
    snprintf(client, sizeof client, "ln_pingpong_%s", role);
    snprintf(out_topic, sizeof out_topic, "%s.%s", prefix, out);
    snprintf(in_topic, sizeof in_topic, "%s.%s", prefix, in);
    ends e;
    int rc = ln_client_create(&e.clnt, client, NULL);
    if (rc < 0)
        bench_fail("ln_client_create", rc);
    if ((rc = ln_publish(e.clnt, &e.pub, out_topic, out_md.name, out_md.hash, out_md.size, NULL)) <
        0)
        bench_fail("ln_publish", rc);
    ln_port_options o;
    ln_port_options_init(&o);
    o.flags = flags;
    o.buffers = buffers;
    if ((rc = ln_subscribe(e.clnt, &e.sub, in_topic, in_md.name, in_md.hash, in_md.size, &o)) < 0)
        bench_fail("ln_subscribe", rc);
    return e;
}

static void put(ln_outport* pub, void* buf, size_t size, uint64_t counter)
{
    memcpy(buf, &counter, sizeof counter);
    int rc = ln_write(pub, buf, size, -1);
    if (rc < 0)
        bench_fail("ln_write", rc);
}

/* The next sample's counter, or 0 with *timed_out set if none came within `timeout`. */
static uint64_t get(ln_inport* sub, void* buf, size_t size, double timeout, int* timed_out)
{
    int rc = ln_read(sub, buf, size, timeout, NULL);
    *timed_out = rc == LN_ETIMEOUT;
    if (*timed_out)
        return 0;
    if (rc < 0)
        bench_fail("ln_read", rc);
    uint64_t counter;
    memcpy(&counter, buf, sizeof counter);
    return counter;
}

static int pong(const char* prefix, bench_md md, uint32_t flags)
{
    ends e = open_ends("pong", prefix, "pong", md, "ping", md, flags, 1);
    void* buf = bench_alloc(md.size);
    uint64_t echoed = 0;
    int timed_out;
    bench_ready();
    while (!stop) {
        get(e.sub, buf, md.size, 0.2, &timed_out); /* wakes up to look at `stop` */
        if (timed_out)
            continue;
        int rc = ln_write(e.pub, buf, md.size, -1);
        if (rc < 0)
            bench_fail("ln_write", rc);
        echoed++;
    }
    ln_client_destroy(e.clnt);
    printf("{\"echoed\": %" PRIu64 "}\n", echoed);
    return 0;
}

/* Ping i until its echo comes (older echoes are answers to resent pings); resend every
 * RETRY_S.  The round trip in ns, or 0 if the ping was resent (not a clean sample). */
static uint64_t round_trip(const ends* e, void* out, void* in, size_t size, uint64_t i,
                           uint64_t* resent)
{
    uint64_t t0 = bench_now_ns(), waited = 0;
    int retried = 0, timed_out;
    put(e->pub, out, size, i);
    for (;;) {
        uint64_t got = get(e->sub, in, size, RETRY_S, &timed_out);
        if (!timed_out && got == i)
            return retried ? 0 : bench_now_ns() - t0;
        if (!timed_out)
            continue;
        if (++waited * RETRY_S >= GIVE_UP_S) {
            fprintf(stderr,
                    "ln_pingpong: no pong for %.0f s: are the topics forwarded between "
                    "the hosts?\n",
                    GIVE_UP_S);
            exit(1);
        }
        (*resent)++;
        retried = 1;
        put(e->pub, out, size, i);
    }
}

static int ping(const char* prefix, bench_md md, uint32_t flags, uint64_t count, uint64_t warmup,
                const char* path)
{
    ends e = open_ends("ping", prefix, "ping", md, "pong", md, flags, 1);
    void *out = bench_alloc(md.size), *in = bench_alloc(md.size);
    uint64_t* rtt = calloc(count ? count : 1, sizeof *rtt);
    uint64_t resent = 0, kept = 0;
    if (!rtt) {
        fprintf(stderr, "ln_pingpong: out of memory\n");
        return 2;
    }
    for (uint64_t i = 0; i < warmup + count; i++) {
        uint64_t t = round_trip(&e, out, in, md.size, i, &resent);
        if (i >= warmup && t != 0)
            rtt[kept++] = t;
    }
    bench_write_samples(path, rtt, kept);
    ln_client_destroy(e.clnt);
    printf("{\"round_trips\": %" PRIu64 ", \"resent\": %" PRIu64 ", \"excluded\": %" PRIu64 "}\n",
           kept, resent, count - kept);
    return 0;
}

/* Counts PREFIX.data from its first sample to the last one or IDLE_S of silence; answers
 * each priming sample on PREFIX.ready, and says DONE there at the end. */
static int sink(const char* prefix, bench_md md, uint32_t flags, uint64_t count)
{
    size_t buffers = SINK_MEMORY / md.size;
    buffers = buffers < 2 ? 2 : buffers > 1024 ? 1024 : buffers;
    ends e =
        open_ends("sink", prefix, "ready", bench_md_for(64), "data", md, flags, (uint32_t)buffers);
    uint8_t *buf = bench_alloc(md.size), ack[64] = {0};
    uint64_t received = 0, primes = 0, disorder = 0, last = 0, first_ns = 0, last_ns = 0;
    int timed_out;
    bench_ready();
    for (;;) {
        uint64_t counter = get(e.sub, buf, md.size, received ? IDLE_S : GIVE_UP_S, &timed_out);
        if (timed_out)
            break;
        if (counter & PRIME) {
            primes++;
            put(e.pub, ack, sizeof ack, counter);
            continue;
        }
        last_ns = bench_now_ns();
        if (received++ == 0)
            first_ns = last_ns;
        else if (counter <= last)
            disorder++;
        last = counter;
        if (counter + 1 >= count)
            break;
    }
    for (int k = 0; k < 3; k++) /* over UDP one may be lost */
        put(e.pub, ack, sizeof ack, DONE);
    if (received == 0)
        fprintf(stderr,
                "ln_pingpong: no sample of %s.data in %.0f s (%" PRIu64 " priming "
                "samples)\n",
                prefix, GIVE_UP_S, primes);
    printf("{\"received\": %" PRIu64 ", \"bytes\": %" PRIu64 ", \"overruns\": %" PRIu64
           ", \"disorder\": %" PRIu64 ", \"elapsed_s\": %.9f, \"primes\": %" PRIu64
           ", \"cpu_s\": %.6f}\n",
           received, received * (uint64_t)md.size, ln_inport_overruns(e.sub), disorder,
           (double)(last_ns - first_ns) * 1e-9, primes, bench_cpu_s());
    ln_client_destroy(e.clnt);
    return received ? 0 : 1;
}

/* Sends priming samples every 10 ms until the sink answers one (so the stream is set up
 * end to end before timing starts), then COUNT samples, then waits for the sink's DONE
 * (keeping its publisher, so nothing in flight is cut off). */
static int source(const char* prefix, bench_md md, uint32_t flags, uint64_t count, double rate)
{
    ends e = open_ends("source", prefix, "data", md, "ready", bench_md_for(64), flags, 1);
    uint8_t *buf = bench_alloc(md.size), ack[64];
    uint64_t primes = 0, start = bench_now_ns();
    int timed_out;
    for (;;) {
        put(e.pub, buf, md.size, PRIME | primes++);
        uint64_t got = get(e.sub, ack, sizeof ack, 0.01, &timed_out);
        if (!timed_out && (got & PRIME) && got != DONE)
            break;
        if ((double)(bench_now_ns() - start) * 1e-9 > GIVE_UP_S) {
            fprintf(stderr,
                    "ln_pingpong: the sink did not answer for %.0f s: are the topics "
                    "forwarded between the hosts?\n",
                    GIVE_UP_S);
            return 1;
        }
    }
    uint64_t t0 = bench_now_ns();
    for (uint64_t i = 0; i < count; i++) {
        if (rate > 0) {
            uint64_t due = t0 + (uint64_t)((double)i * 1e9 / rate);
            struct timespec ts = {(time_t)(due / 1000000000u), (long)(due % 1000000000u)};
            while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, NULL) != 0) {
            }
        }
        put(e.pub, buf, md.size, i);
    }
    uint64_t t1 = bench_now_ns();
    int done = 0;
    while (!done) {
        uint64_t got = get(e.sub, ack, sizeof ack, GIVE_UP_S, &timed_out);
        done = timed_out || got == DONE;
    }
    printf("{\"sent\": %" PRIu64 ", \"elapsed_s\": %.9f, \"primes\": %" PRIu64
           ", \"done_seen\": %s, \"cpu_s\": %.6f}\n",
           count, (double)(t1 - t0) * 1e-9, primes, timed_out ? "false" : "true", bench_cpu_s());
    ln_client_destroy(e.clnt);
    return 0;
}

int main(int argc, char** argv)
{
    const char* role = argc > 1 ? argv[1] : "";
    int ok = (argc == 5 && strcmp(role, "pong") == 0) || (argc == 8 && strcmp(role, "ping") == 0) ||
             (argc == 6 && strcmp(role, "sink") == 0) || (argc == 7 && strcmp(role, "source") == 0);
    if (!ok) {
        fputs(usage, stderr);
        return 2;
    }
    struct sigaction sa = {.sa_handler = on_signal};
    sigaction(SIGTERM, &sa, NULL);
    sigaction(SIGINT, &sa, NULL);
    bench_md md = bench_md_for(strtoull(argv[3], NULL, 10));
    uint32_t flags = transport_flags(argv[4]);
    if (strcmp(role, "pong") == 0)
        return pong(argv[2], md, flags);
    uint64_t count = strtoull(argv[5], NULL, 10);
    if (strcmp(role, "ping") == 0)
        return ping(argv[2], md, flags, count, strtoull(argv[6], NULL, 10), argv[7]);
    if (strcmp(role, "sink") == 0)
        return sink(argv[2], md, flags, count);
    return source(argv[2], md, flags, count, strtod(argv[6], NULL));
}
