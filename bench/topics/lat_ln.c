/* lat_ln.c — ping-pong latency through two libln topics between two processes; ping times
 * every round trip.  copy: ln_write/ln_read of the whole sample; zc: loan/commit and
 * borrow/release touching only the first and last 8 bytes; full: zero-copy moving the whole
 * sample (ping copies its buffer into the loan and the reply out of the borrow, pong copies
 * the borrowed sample into its loan).  Manager from $LN_MANAGER. */
#include <inttypes.h>

#include "bench_common.h"

static const char usage[] =
    "usage: lat_ln pong PREFIX SIZE copy|zc|full TOTAL [WARMUP]    echo TOTAL samples\n"
    "       lat_ln ping PREFIX SIZE copy|zc|full COUNT WARMUP OUT  COUNT round trips (ns) "
    "to OUT\n"
    "Both print {\"minflt\": faults, \"samples\": n} over the round trips after WARMUP.\n";

typedef struct ends {
    ln_client* clnt;
    ln_outport* pub;
    ln_inport* sub;
    size_t size;
    int zc;   /* zero-copy (zc or full) */
    int full; /* full: the whole sample is copied into loans and out of borrows */
} ends;

static void open_ends(ends* e, const char* prefix, const char* role, size_t size, const char* mode)
{
    bench_md md = bench_md_for(size);
    char out[256], in[256];
    int ping = strcmp(role, "ping") == 0;
    snprintf(out, sizeof out, "%s.%s", prefix, ping ? "ping" : "pong");
    snprintf(in, sizeof in, "%s.%s", prefix, ping ? "pong" : "ping");
    int rc = ln_client_create(&e->clnt, ping ? "lat_ln_ping" : "lat_ln_pong", NULL);
    if (rc < 0)
        bench_fail("ln_client_create", rc);
    if ((rc = ln_publish(e->clnt, &e->pub, out, md.name, md.hash, md.size, NULL)) < 0)
        bench_fail("ln_publish", rc);
    if ((rc = ln_subscribe(e->clnt, &e->sub, in, md.name, md.hash, md.size, NULL)) < 0)
        bench_fail("ln_subscribe", rc);
    e->size = size;
    e->full = strcmp(mode, "full") == 0;
    e->zc = e->full || strcmp(mode, "zc") == 0;
}

/* Send sample `i` (copy mode: from buf). */
static void send_one(const ends* e, uint64_t i, void* buf)
{
    int rc;
    if (!e->zc) {
        memcpy(buf, &i, sizeof i);
        if ((rc = ln_write(e->pub, buf, e->size, -1)) < 0)
            bench_fail("ln_write", rc);
        return;
    }
    void* slot;
    if ((rc = ln_write_loan(e->pub, &slot, -1)) < 0)
        bench_fail("ln_write_loan", rc);
    if (e->full) {
        bench_stamp(buf, e->size, i);
        memcpy(slot, buf, e->size);
    } else {
        bench_stamp(slot, e->size, i);
    }
    if ((rc = ln_write_commit(e->pub)) < 0)
        bench_fail("ln_write_commit", rc);
}

/* full: copy the borrowed sample whole into `buf` (ping) or into a loan sent back (echo);
 * returns its counter. */
static uint64_t receive_full(const ends* e, const void* sample, void* buf, int echo)
{
    int rc;
    void* slot = buf;
    if (echo && (rc = ln_write_loan(e->pub, &slot, -1)) < 0)
        bench_fail("ln_write_loan", rc);
    memcpy(slot, sample, e->size);
    if ((rc = ln_read_release(e->sub)) < 0)
        bench_fail("ln_read_release", rc);
    uint64_t counter = bench_check(slot, e->size, "lat_ln");
    if (echo && (rc = ln_write_commit(e->pub)) < 0)
        bench_fail("ln_write_commit", rc);
    return counter;
}

/* Receive one sample and return its counter; with `echo` send it straight back. */
static uint64_t receive_one(const ends* e, void* buf, int echo)
{
    int rc;
    uint64_t counter;
    if (!e->zc) {
        if ((rc = ln_read(e->sub, buf, e->size, -1, NULL)) < 0)
            bench_fail("ln_read", rc);
        memcpy(&counter, buf, sizeof counter);
        if (echo && (rc = ln_write(e->pub, buf, e->size, -1)) < 0)
            bench_fail("ln_write", rc);
        return counter;
    }
    const void* sample;
    if ((rc = ln_read_borrow(e->sub, &sample, -1, NULL)) < 0)
        bench_fail("ln_read_borrow", rc);
    if (e->full)
        return receive_full(e, sample, buf, echo);
    counter = bench_check(sample, e->size, "lat_ln");
    void* slot = NULL;
    if (echo && (rc = ln_write_loan(e->pub, &slot, -1)) < 0)
        bench_fail("ln_write_loan", rc);
    if ((rc = ln_read_release(e->sub)) < 0)
        bench_fail("ln_read_release", rc);
    if (echo) {
        bench_stamp(slot, e->size, counter);
        if ((rc = ln_write_commit(e->pub)) < 0)
            bench_fail("ln_write_commit", rc);
    }
    return counter;
}

/* Minor page faults since `since` (bench_minflt), for the driver. */
static void print_faults(uint64_t since, uint64_t samples)
{
    printf("{\"minflt\": %" PRIu64 ", \"samples\": %" PRIu64 "}\n", bench_minflt() - since,
           samples);
    fflush(stdout);
}

int main(int argc, char** argv)
{
    if (argc < 6 || (strcmp(argv[1], "ping") != 0 && strcmp(argv[1], "pong") != 0) ||
        (strcmp(argv[1], "ping") == 0 && argc < 8)) {
        fputs(usage, stderr);
        return 2;
    }
    int ping = strcmp(argv[1], "ping") == 0;
    size_t size = strtoull(argv[3], NULL, 10);
    ends e;
    open_ends(&e, argv[2], argv[1], size, argv[4]);
    uint64_t count = strtoull(argv[5], NULL, 10);
    void* buf = bench_alloc(size);
    if (!ping) {
        uint64_t warmup = argc > 6 ? strtoull(argv[6], NULL, 10) : 0, faults = 0;
        bench_ready();
        for (uint64_t i = 0; i < count; i++) {
            if (i == warmup)
                faults = bench_minflt();
            receive_one(&e, buf, 1);
        }
        print_faults(faults, count > warmup ? count - warmup : 0);
        ln_client_destroy(e.clnt);
        return 0;
    }
    uint64_t warmup = strtoull(argv[6], NULL, 10), faults = 0;
    uint64_t* rtt =
        bench_alloc((count ? count : 1) * sizeof(uint64_t)); /* touched: no faults later */
    void* reply = bench_alloc(size);
    for (uint64_t i = 0; rtt && i < warmup + count; i++) {
        if (i == warmup)
            faults = bench_minflt();
        uint64_t t0 = bench_now_ns();
        send_one(&e, i, buf);
        uint64_t got = receive_one(&e, reply, 0);
        uint64_t t1 = bench_now_ns();
        if (got != i) {
            fprintf(stderr, "lat_ln: round trip %llu came back as %llu\n", (unsigned long long)i,
                    (unsigned long long)got);
            return 1;
        }
        if (i >= warmup)
            rtt[i - warmup] = t1 - t0;
    }
    if (!rtt)
        return 2;
    print_faults(faults, count);
    bench_write_samples(argv[7], rtt, count);
    ln_client_destroy(e.clnt);
    return 0;
}
