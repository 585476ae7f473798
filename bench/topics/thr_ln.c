/* thr_ln.c — throughput of one libln topic: a publisher writing COUNT samples as fast as it
 * can into a queued subscriber in another process.  Each side prints one JSON line. */
#include <inttypes.h>

#include "bench_common.h"

static const char usage[] =
    "usage: thr_ln sub TOPIC SIZE COUNT BUFFERS      read until the last sample or 2 s idle\n"
    "       thr_ln pub TOPIC SIZE COUNT wait|nowait  wait: LN_PUBLISH_WAIT_FOR_SUBSCRIBERS\n";

static int subscriber(ln_client* clnt, const char* topic, bench_md md, uint64_t count,
                      uint32_t buffers)
{
    ln_port_options o;
    ln_port_options_init(&o);
    o.buffers = buffers;
    ln_inport* sub;
    int rc = ln_subscribe(clnt, &sub, topic, md.name, md.hash, md.size, &o);
    if (rc < 0)
        bench_fail("ln_subscribe", rc);
    uint8_t* buf = bench_alloc(md.size);
    uint64_t received = 0, disorder = 0, last = 0, first_ns = 0, last_ns = 0;
    bench_ready();
    while (received == 0 || last + 1 < count) {
        rc = ln_read(sub, buf, md.size, received ? 2.0 : 60.0, NULL);
        if (rc == LN_ETIMEOUT)
            break;
        if (rc < 0)
            bench_fail("ln_read", rc);
        last_ns = bench_now_ns();
        uint64_t counter;
        memcpy(&counter, buf, sizeof counter);
        if (received++ == 0)
            first_ns = last_ns;
        else if (counter <= last)
            disorder++;
        last = counter;
    }
    printf("{\"received\": %" PRIu64 ", \"overruns\": %" PRIu64 ", \"disorder\": %" PRIu64
           ", \"elapsed_s\": %.9f}\n",
           received, ln_inport_overruns(sub), disorder, (double)(last_ns - first_ns) * 1e-9);
    return 0;
}

static int publisher(ln_client* clnt, const char* topic, bench_md md, uint64_t count, int wait)
{
    ln_port_options o;
    ln_port_options_init(&o);
    o.flags = wait ? LN_PUBLISH_WAIT_FOR_SUBSCRIBERS : 0;
    ln_outport* pub;
    int rc = ln_publish(clnt, &pub, topic, md.name, md.hash, md.size, &o);
    if (rc < 0)
        bench_fail("ln_publish", rc);
    uint8_t* buf = bench_alloc(md.size);
    bench_ready();
    uint64_t t0 = bench_now_ns();
    for (uint64_t i = 0; i < count; i++) {
        memcpy(buf, &i, sizeof i);
        if ((rc = ln_write(pub, buf, md.size, -1)) < 0)
            bench_fail("ln_write", rc);
    }
    uint64_t t1 = bench_now_ns();
    printf("{\"sent\": %" PRIu64 ", \"elapsed_s\": %.9f}\n", count, (double)(t1 - t0) * 1e-9);
    return 0;
}

int main(int argc, char** argv)
{
    if (argc != 6 || (strcmp(argv[1], "sub") != 0 && strcmp(argv[1], "pub") != 0)) {
        fputs(usage, stderr);
        return 2;
    }
    bench_md md = bench_md_for(strtoull(argv[3], NULL, 10));
    uint64_t count = strtoull(argv[4], NULL, 10);
    ln_client* clnt;
    int rc = ln_client_create(&clnt, "thr_ln", NULL);
    if (rc < 0)
        bench_fail("ln_client_create", rc);
    if (strcmp(argv[1], "sub") == 0)
        rc = subscriber(clnt, argv[2], md, count, (uint32_t)strtoul(argv[5], NULL, 10));
    else
        rc = publisher(clnt, argv[2], md, count, strcmp(argv[5], "wait") == 0);
    ln_client_destroy(clnt);
    return rc;
}
