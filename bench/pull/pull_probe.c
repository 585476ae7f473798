/* pull_probe.c — the programs of the pull-topic benchmark (bench/pull/bench_pull.py) and of
 * the loss tests (tests/python/pull_lossy), one binary in three roles:
 *
 *   pull_probe pub TOPIC PERIOD_US
 *       publishes lnbench/sample_64 (counter = seq) on absolute deadlines every PERIOD_US
 *       (a late cycle is published late, never skipped, so seq n is due at t0 + (n-1)·P);
 *       prints "ready" after the first sample and runs until killed.
 *   pull_probe push TOPIC SECONDS OUT
 *       subscribes to TOPIC over the daemons' UDP forwarding (LN_SUBSCRIBE_UDP, queued) and
 *       records every sample it reads for SECONDS.
 *   pull_probe pull HOST:PORT URI SECONDS OUT [--naive] [--window K] [--deadline MS]
 *                   [--poll MS] [--boot N] [--rtt N] [--seed S]
 *       subscribes to the pull topic URI served at HOST:PORT with libln_pull (hardened by
 *       default: k = 3, t_max = 100 ms); --naive is the seed's DIT, --poll MS a fixed-rate
 *       poll of /sync.  With --rtt N it then sends N Interests, one at a time, for a sample
 *       that is already produced and times each answer (CLOCK_MONOTONIC) on its own socket.
 *
 * OUT gets one JSON object: per received sample [seq, publish µs, receive µs] (both
 * CLOCK_REALTIME: every namespace of the machine shares the clock), the consumer's stats and
 * events ([µs, event, seq, t ms]: 1 timeout, 2 NACK, 3 sync) and the RTTs in µs.  The
 * driver computes delivery, age of information and rates from them. */
#define _GNU_SOURCE 1

#include <arpa/inet.h>
#include <errno.h>
#include <inttypes.h>
#include <netinet/in.h>
#include <poll.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include <ln/ln.h>
#include <ln/ndn.h>
#include <ln/pull.h>

#include "bench_messages.h"

#define MAX_RECORDS 2000000u
#define MAX_EVENTS 200000u
#define MAX_RTT 10000u

typedef struct record {
    uint64_t seq, publish_us, receive_us;
} record;
typedef struct event {
    uint64_t at_us, seq;
    int kind;
    uint32_t t_ms;
} event;

static record* records;
static size_t nrecords;
static event* events;
static size_t nevents;
static uint64_t rtts[MAX_RTT];
static size_t nrtt, rtt_sent;
static uint64_t received_packets;

static void die(const char* what)
{
    fprintf(stderr, "pull_probe: %s: %s\n", what, strerror(errno));
    exit(2);
}

static void ln_die(const char* what, int rc)
{
    fprintf(stderr, "pull_probe: %s: %s: %s\n", what, ln_error_name(rc), ln_last_error());
    exit(2);
}

static uint64_t now_us(clockid_t clock)
{
    struct timespec ts;
    clock_gettime(clock, &ts);
    return (uint64_t)ts.tv_sec * 1000000u + (uint64_t)ts.tv_nsec / 1000u;
}

static uint32_t now_ms(void) { return (uint32_t)(now_us(CLOCK_MONOTONIC) / 1000u); }

static void add_record(uint64_t seq, uint64_t publish_us)
{
    if (nrecords < MAX_RECORDS)
        records[nrecords++] = (record){seq, publish_us, now_us(CLOCK_REALTIME)};
}

/* ---- pub ------------------------------------------------------------------------------ */

static _Noreturn void run_pub(const char* topic, uint64_t period_us)
{
    ln_client* clnt;
    ln_outport* pub;
    int rc = ln_client_create(&clnt, "pull_probe_pub", NULL);
    if (rc < 0)
        ln_die("ln_client_create", rc);
    if ((rc = ln_publish(clnt, &pub, topic, LNBENCH_SAMPLE_64_MD, NULL)) < 0)
        ln_die("ln_publish", rc);
    lnbench_sample_64_t s;
    memset(&s, 0, sizeof s);
    struct timespec next;
    clock_gettime(CLOCK_MONOTONIC, &next);
    for (uint64_t n = 1;; n++) {
        s.counter = n;
        if ((rc = ln_write(pub, &s, sizeof s, -1)) < 0)
            ln_die("ln_write", rc);
        if (n == 1) {
            printf("ready\n");
            fflush(stdout);
        }
        uint64_t ns = (uint64_t)next.tv_nsec + period_us * 1000u;
        next.tv_sec += (time_t)(ns / 1000000000u);
        next.tv_nsec = (long)(ns % 1000000000u);
        while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, NULL) == EINTR) {
        }
    }
}

/* ---- push ----------------------------------------------------------------------------- */

static void run_push(const char* topic, double seconds)
{
    ln_client* clnt;
    ln_inport* sub;
    int rc = ln_client_create(&clnt, "pull_probe_push", NULL);
    if (rc < 0)
        ln_die("ln_client_create", rc);
    ln_port_options o;
    ln_port_options_init(&o);
    o.flags = LN_SUBSCRIBE_UDP;
    o.buffers = 256;
    if ((rc = ln_subscribe(clnt, &sub, topic, LNBENCH_SAMPLE_64_MD, &o)) < 0)
        ln_die("ln_subscribe", rc);
    uint64_t end = now_us(CLOCK_MONOTONIC) + (uint64_t)(seconds * 1e6);
    lnbench_sample_64_t s;
    while (now_us(CLOCK_MONOTONIC) < end) {
        ln_sample_info info;
        rc = ln_read(sub, &s, sizeof s, 0.05, &info);
        if (rc == LN_ETIMEOUT)
            continue;
        if (rc < 0)
            ln_die("ln_read", rc);
        received_packets++;
        add_record(info.seq, (uint64_t)info.timestamp_ns / 1000u);
    }
    ln_client_destroy(clnt);
}

/* ---- pull ----------------------------------------------------------------------------- */

typedef struct pull_ctx {
    int fd;
    struct sockaddr_in peer;
} pull_ctx;

static void on_send(void* user, const uint8_t* packet, size_t size)
{
    pull_ctx* c = user;
    /* a refused send is a lost packet: the consumer times out and asks again */
    (void)sendto(c->fd, packet, size, 0, (struct sockaddr*)&c->peer, sizeof c->peer);
}

static void on_data(void* user, uint64_t seq, const uint8_t* payload, size_t size,
                    uint64_t publish_us)
{
    (void)user, (void)payload, (void)size;
    add_record(seq, publish_us);
}

static void on_event(void* user, int kind, uint64_t seq, uint32_t t_ms)
{
    (void)user;
    if (nevents < MAX_EVENTS)
        events[nevents++] = (event){now_us(CLOCK_REALTIME), seq, kind, t_ms};
}

static int open_socket(const char* hostport, struct sockaddr_in* peer)
{
    char host[64];
    const char* colon = strrchr(hostport, ':');
    if (!colon || (size_t)(colon - hostport) >= sizeof host) {
        fprintf(stderr, "pull_probe: HOST:PORT expected, got %s\n", hostport);
        exit(2);
    }
    memcpy(host, hostport, (size_t)(colon - hostport));
    host[colon - hostport] = 0;
    memset(peer, 0, sizeof *peer);
    peer->sin_family = AF_INET;
    peer->sin_port = htons((uint16_t)atoi(colon + 1));
    if (inet_pton(AF_INET, host, &peer->sin_addr) != 1) {
        fprintf(stderr, "pull_probe: not an IPv4 address: %s\n", host);
        exit(2);
    }
    int fd = socket(AF_INET, SOCK_DGRAM, 0);
    if (fd < 0)
        die("socket");
    return fd;
}

static ln_pull_sub sub; /* static: the probe shows the consumer needs no heap */

static void run_pull(pull_ctx* c, const char* uri, const ln_pull_options* o, double seconds,
                     uint32_t seed)
{
    int rc = ln_pull_start(&sub, uri, o, on_send, on_data, on_event, c, now_ms(), seed);
    if (rc < 0) {
        fprintf(stderr, "pull_probe: ln_pull_start: %s\n", ln_ndn_strerror(rc));
        exit(2);
    }
    uint64_t end = now_us(CLOCK_MONOTONIC) + (uint64_t)(seconds * 1e6);
    uint8_t buf[9000];
    for (;;) {
        uint64_t now = now_us(CLOCK_MONOTONIC);
        if (now >= end)
            break;
        uint32_t wait = ln_pull_poll(&sub, now_ms());
        uint64_t left_ms = (end - now) / 1000u + 1u;
        struct pollfd p = {c->fd, POLLIN, 0};
        int n = poll(&p, 1, (int)(wait < left_ms ? wait : left_ms));
        if (n < 0 && errno != EINTR)
            die("poll");
        while (n > 0) {
            ssize_t got = recv(c->fd, buf, sizeof buf, MSG_DONTWAIT);
            if (got < 0) {
                if (errno == EAGAIN || errno == EWOULDBLOCK)
                    break;
                if (errno == ECONNREFUSED) /* ICMP of an earlier datagram: count as lost */
                    continue;
                die("recv");
            }
            received_packets++;
            ln_pull_receive(&sub, buf, (size_t)got, now_ms());
        }
    }
}

/* Interests for an already-produced seq, one at a time: the pure network and stack time. */
static void measure_rtt(const struct sockaddr_in* peer, const char* uri, unsigned count)
{
    uint64_t seq = sub.latest_seq > 2 ? sub.latest_seq - 2 : 0;
    if (seq == 0)
        return;
    int fd = socket(AF_INET, SOCK_DGRAM, 0);
    if (fd < 0)
        die("socket");
    uint8_t name[LN_PULL_MAX_NAME + 16], pkt[256], buf[9000];
    int base = ln_ndn_name_from_uri(name, sizeof name, uri);
    if (base < 0) {
        fprintf(stderr, "pull_probe: rtt name: %s\n", ln_ndn_strerror(base));
        exit(2);
    }
    for (unsigned i = 0; i < count && nrtt < MAX_RTT; i++) {
        /* the producer's history is short at fast rates: ask for latest - 2 as last heard */
        int size = ln_ndn_name_append_seq(name, sizeof name, (size_t)base, seq);
        ln_ndn_interest in;
        memset(&in, 0, sizeof in);
        in.name = (ln_ndn_bytes){name, (size_t)(size < 0 ? 0 : size)};
        in.nonce = 0x9e3779b9u * (i + 1u);
        in.has_nonce = 1;
        in.lifetime_ms = 250;
        int len = size < 0 ? size : ln_ndn_encode_interest(pkt, sizeof pkt, &in);
        if (len < 0) {
            fprintf(stderr, "pull_probe: rtt interest: %s\n", ln_ndn_strerror(len));
            exit(2);
        }
        uint64_t sent = now_us(CLOCK_MONOTONIC);
        rtt_sent++;
        (void)sendto(fd, pkt, (size_t)len, 0, (const struct sockaddr*)peer, sizeof *peer);
        for (;;) {
            uint64_t waited = (now_us(CLOCK_MONOTONIC) - sent) / 1000u;
            if (waited >= 250)
                break; /* lost on the way there or back */
            struct pollfd p = {fd, POLLIN, 0};
            if (poll(&p, 1, (int)(250 - waited)) <= 0)
                continue;
            ssize_t got = recv(fd, buf, sizeof buf, MSG_DONTWAIT);
            ln_ndn_packet pk;
            ln_ndn_pull_content pc;
            if (got > 0 && ln_ndn_decode(buf, (size_t)got, &pk) == LN_NDN_OK &&
                pk.type == LN_NDN_T_DATA && pk.data.name.size == (size_t)size &&
                memcmp(pk.data.name.data, name, (size_t)size) == 0) {
                uint64_t rtt = now_us(CLOCK_MONOTONIC) - sent;
                int ok = ln_ndn_decode_pull_content(pk.data.content, &pc) == LN_NDN_OK;
                if (pk.data.content_type != LN_NDN_CONTENT_NACK)
                    rtts[nrtt++] = rtt; /* a NACK (too old by now) is not a sample's RTT */
                if (ok && pc.latest_seq > 2)
                    seq = pc.latest_seq - 2;
                break;
            }
        }
    }
    close(fd);
}

/* ---- output --------------------------------------------------------------------------- */

static void write_json(const char* path, const char* mode, uint64_t start_us, uint64_t end_us,
                       int pull)
{
    FILE* f = fopen(path, "w");
    if (!f)
        die(path);
    fprintf(f,
            "{\"mode\": \"%s\", \"start_us\": %" PRIu64 ", \"end_us\": %" PRIu64
            ", \"received_packets\": %" PRIu64 ", \"samples\": [",
            mode, start_us, end_us, received_packets);
    for (size_t i = 0; i < nrecords; i++)
        fprintf(f, "%s[%" PRIu64 ", %" PRIu64 ", %" PRIu64 "]", i ? ", " : "", records[i].seq,
                records[i].publish_us, records[i].receive_us);
    fprintf(f, "], \"events\": [");
    for (size_t i = 0; i < nevents; i++)
        fprintf(f, "%s[%" PRIu64 ", %d, %" PRIu64 ", %" PRIu32 "]", i ? ", " : "", events[i].at_us,
                events[i].kind, events[i].seq, events[i].t_ms);
    fprintf(f, "], \"rtt_sent\": %zu, \"rtt_us\": [", rtt_sent);
    for (size_t i = 0; i < nrtt; i++)
        fprintf(f, "%s%" PRIu64, i ? ", " : "", rtts[i]);
    fprintf(f, "]");
    if (pull) {
        const ln_pull_stats* s = &sub.stats;
        fprintf(f,
                ", \"stats\": {\"interests\": %" PRIu32 ", \"syncs\": %" PRIu32
                ", \"data\": %" PRIu32 ", \"timeouts\": %" PRIu32 ", \"nacks\": %" PRIu32
                ", \"late\": %" PRIu32 ", \"bad\": %" PRIu32 ", \"refreshes\": %" PRIu32
                "}, \"latest_seq\": %" PRIu64 ", \"t_ms\": %" PRIu32 ", \"window\": %u"
                ", \"srtt_us\": %" PRIu32 ", \"state_bytes\": %zu",
                s->interests, s->syncs, s->data, s->timeouts, s->nacks, s->late, s->bad,
                s->refreshes, sub.latest_seq, sub.t_ms, (unsigned)sub.window, sub.srtt_us,
                sizeof sub);
    }
    fprintf(f, "}\n");
    if (fclose(f) != 0)
        die(path);
    /* the line the driver waits for (bench/network's managed cases read stdout) */
    printf("{\"mode\": \"%s\", \"samples\": %zu, \"out\": \"%s\"}\n", mode, nrecords, path);
}

static void usage(void)
{
    fprintf(stderr,
            "usage: pull_probe pub TOPIC PERIOD_US\n"
            "       pull_probe push TOPIC SECONDS OUT\n"
            "       pull_probe pull HOST:PORT URI SECONDS OUT [--naive] [--window K]\n"
            "                  [--deadline MS] [--poll MS] [--boot N] [--rtt N] [--seed S]\n");
    exit(2);
}

int main(int argc, char** argv)
{
    if (argc < 2)
        usage();
    setvbuf(stdout, NULL, _IOLBF, 0);
    if (strcmp(argv[1], "pub") == 0 && argc == 4)
        run_pub(argv[2], strtoull(argv[3], NULL, 10));
    records = calloc(MAX_RECORDS, sizeof *records);
    events = calloc(MAX_EVENTS, sizeof *events);
    if (!records || !events)
        die("calloc");
    uint64_t start = now_us(CLOCK_REALTIME);
    if (strcmp(argv[1], "push") == 0 && argc == 5) {
        run_push(argv[2], atof(argv[3]));
        write_json(argv[4], "push", start, now_us(CLOCK_REALTIME), 0);
        return 0;
    }
    if (strcmp(argv[1], "pull") != 0 || argc < 6)
        usage();
    ln_pull_options o;
    unsigned window = 0, deadline = 100, poll_ms = 0, boot = 0, rtt = 0, naive = 0;
    uint32_t seed = (uint32_t)getpid();
    for (int i = 6; i < argc; i++) {
        const char* a = argv[i];
        if (strcmp(a, "--naive") == 0) {
            naive = 1;
            continue;
        }
        if (i + 1 >= argc)
            usage();
        unsigned v = (unsigned)strtoul(argv[++i], NULL, 10);
        if (strcmp(a, "--window") == 0)
            window = v;
        else if (strcmp(a, "--deadline") == 0)
            deadline = v;
        else if (strcmp(a, "--poll") == 0)
            poll_ms = v;
        else if (strcmp(a, "--boot") == 0)
            boot = v;
        else if (strcmp(a, "--rtt") == 0)
            rtt = v;
        else if (strcmp(a, "--seed") == 0)
            seed = v;
        else
            usage();
    }
    if (naive)
        ln_pull_options_naive(&o);
    else
        ln_pull_options_hardened(&o, deadline);
    if (window)
        o.window = (uint8_t)window;
    if (boot)
        o.boot_after = (uint8_t)boot;
    o.poll_ms = poll_ms;
    pull_ctx c;
    c.fd = open_socket(argv[2], &c.peer);
    run_pull(&c, argv[3], &o, atof(argv[4]), seed);
    uint64_t end = now_us(CLOCK_REALTIME);
    if (rtt)
        measure_rtt(&c.peer, argv[3], rtt);
    write_json(argv[5], poll_ms ? "poll" : naive ? "naive" : "hardened", start, end, 1);
    return 0;
}
