/* thr_ln.c — throughput of one libln topic: a publisher writing samples as fast as it can
 * into a queued subscriber in another process, by copy (ln_write/ln_read) or zero-copy
 * (loan/commit, borrow/release; zc touches the first and last 8 bytes, full copies a whole
 * source buffer into each loan and each borrowed sample out whole).  One JSON line each. */
#include <inttypes.h>

#include "bench_common.h"

static const char usage[] =
    "usage: thr_ln sub TOPIC SIZE COUNT BUFFERS [copy|zc|full WARM]\n"
    "           read until the last sample or 2 s idle\n"
    "       thr_ln pub TOPIC SIZE COUNT wait|nowait [copy|zc|full WARM SECONDS]\n"
    "           wait: LN_PUBLISH_WAIT_FOR_SUBSCRIBERS; after SECONDS the next sample is the\n"
    "           last (counter COUNT-1).  Minor faults are counted from sample WARM on.\n";

typedef struct run {
    const char* topic;
    bench_md md;
    uint64_t count, warm;
    int zc;   /* zero-copy (zc or full) */
    int full; /* full: whole payloads into loans and out of borrows */
} run;

/* One sample into *counter; 1 if read, 0 after the timeout, -1 if a zero-copy sample was
 * overwritten while borrowed (counted as an overrun by libln, not returned). */
static int read_one(ln_inport* sub, const run* r, uint8_t* buf, double timeout, uint64_t* counter)
{
    int rc;
    if (!r->zc) {
        rc = ln_read(sub, buf, r->md.size, timeout, NULL);
        if (rc == LN_ETIMEOUT)
            return 0;
        if (rc < 0)
            bench_fail("ln_read", rc);
        memcpy(counter, buf, sizeof *counter);
        return 1;
    }
    const void* sample;
    rc = ln_read_borrow(sub, &sample, timeout, NULL);
    if (rc == LN_ETIMEOUT)
        return 0;
    if (rc < 0)
        bench_fail("ln_read_borrow", rc);
    uint64_t first, last;
    const uint8_t* data = sample;
    if (r->full) { /* the whole sample out before it is released */
        memcpy(buf, sample, r->md.size);
        data = buf;
    }
    memcpy(&first, data, sizeof first);
    memcpy(&last, data + r->md.size - sizeof last, sizeof last);
    rc = ln_read_release(sub);
    if (rc == LN_EOVERRUN)
        return -1;
    if (rc < 0)
        bench_fail("ln_read_release", rc);
    if (first != last) {
        fprintf(stderr, "thr_ln: torn sample %" PRIu64 "/%" PRIu64 "\n", first, last);
        exit(1);
    }
    *counter = first;
    return 1;
}

static int subscriber(ln_client* clnt, const run* r, uint32_t buffers)
{
    ln_port_options o;
    ln_port_options_init(&o);
    o.buffers = buffers;
    ln_inport* sub;
    int rc = ln_subscribe(clnt, &sub, r->topic, r->md.name, r->md.hash, r->md.size, &o);
    if (rc < 0)
        bench_fail("ln_subscribe", rc);
    uint8_t* buf = r->zc && !r->full ? NULL : bench_alloc(r->md.size);
    uint64_t received = 0, disorder = 0, last = 0, first_ns = 0, last_ns = 0;
    uint64_t faults = 0, fault_samples = 0;
    int counting = 0;
    bench_ready();
    while (received == 0 || last + 1 < r->count) {
        uint64_t counter;
        rc = read_one(sub, r, buf, received ? 2.0 : 60.0, &counter);
        if (rc == 0)
            break;
        if (rc < 0)
            continue;
        last_ns = bench_now_ns();
        if (!counting && counter >= r->warm) {
            counting = 1;
            faults = bench_minflt();
        }
        fault_samples += counting;
        if (received++ == 0)
            first_ns = last_ns;
        else if (counter <= last)
            disorder++;
        last = counter;
    }
    printf("{\"received\": %" PRIu64 ", \"overruns\": %" PRIu64 ", \"disorder\": %" PRIu64
           ", \"elapsed_s\": %.9f, \"minflt\": %" PRIu64 ", \"fault_samples\": %" PRIu64 "}\n",
           received, ln_inport_overruns(sub), disorder, (double)(last_ns - first_ns) * 1e-9,
           counting ? bench_minflt() - faults : 0, fault_samples);
    return 0;
}

static void write_one(ln_outport* pub, const run* r, uint8_t* buf, uint64_t counter)
{
    int rc;
    if (!r->zc) {
        memcpy(buf, &counter, sizeof counter);
        if ((rc = ln_write(pub, buf, r->md.size, -1)) < 0)
            bench_fail("ln_write", rc);
        return;
    }
    void* slot;
    if ((rc = ln_write_loan(pub, &slot, -1)) < 0)
        bench_fail("ln_write_loan", rc);
    if (r->full) {
        bench_stamp(buf, r->md.size, counter);
        memcpy(slot, buf, r->md.size);
    } else {
        bench_stamp(slot, r->md.size, counter);
    }
    if ((rc = ln_write_commit(pub)) < 0)
        bench_fail("ln_write_commit", rc);
}

static int publisher(ln_client* clnt, const run* r, int wait, double seconds)
{
    ln_port_options o;
    ln_port_options_init(&o);
    o.flags = wait ? LN_PUBLISH_WAIT_FOR_SUBSCRIBERS : 0;
    ln_outport* pub;
    int rc = ln_publish(clnt, &pub, r->topic, r->md.name, r->md.hash, r->md.size, &o);
    if (rc < 0)
        bench_fail("ln_publish", rc);
    uint8_t* buf = r->zc && !r->full ? NULL : bench_alloc(r->md.size);
    bench_ready();
    uint64_t t0 = bench_now_ns(), faults = bench_minflt(), sent = 0;
    uint64_t stop_ns = seconds > 0 ? t0 + (uint64_t)(seconds * 1e9) : UINT64_MAX;
    for (uint64_t i = 0; i < r->count; i++) {
        if (i == r->warm)
            faults = bench_minflt();
        /* out of time: this one is the last, so the subscriber stops at once */
        int last = (i & 15) == 0 && bench_now_ns() > stop_ns;
        write_one(pub, r, buf, last ? r->count - 1 : i);
        sent++;
        if (last)
            break;
    }
    uint64_t t1 = bench_now_ns();
    printf("{\"sent\": %" PRIu64 ", \"elapsed_s\": %.9f, \"minflt\": %" PRIu64
           ", \"fault_samples\": %" PRIu64 "}\n",
           sent, (double)(t1 - t0) * 1e-9, sent > r->warm ? bench_minflt() - faults : 0,
           sent > r->warm ? sent - r->warm : 0);
    return 0;
}

int main(int argc, char** argv)
{
    int is_sub = argc >= 6 && strcmp(argv[1], "sub") == 0;
    int is_pub = argc >= 6 && strcmp(argv[1], "pub") == 0;
    if ((!is_sub && !is_pub) || argc > (is_sub ? 8 : 9)) {
        fputs(usage, stderr);
        return 2;
    }
    int full = argc > 6 && strcmp(argv[6], "full") == 0;
    run r = {argv[2],
             bench_md_for(strtoull(argv[3], NULL, 10)),
             strtoull(argv[4], NULL, 10),
             argc > 7 ? strtoull(argv[7], NULL, 10) : 0,
             full || (argc > 6 && strcmp(argv[6], "zc") == 0),
             full};
    ln_client* clnt;
    int rc = ln_client_create(&clnt, "thr_ln", NULL);
    if (rc < 0)
        bench_fail("ln_client_create", rc);
    if (is_sub)
        rc = subscriber(clnt, &r, (uint32_t)strtoul(argv[5], NULL, 10));
    else
        rc = publisher(clnt, &r, strcmp(argv[5], "wait") == 0, argc > 8 ? atof(argv[8]) : 0);
    ln_client_destroy(clnt);
    return rc;
}
