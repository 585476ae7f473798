/* pub_cost.c — what a publish costs when no reader sleeps (so no system call is due): ns per
 * ln_write or loan+commit in a tight loop, beside the same loop with a memcpy into a plain
 * buffer, plus cycles/instructions per op where hardware counters exist.  One JSON line. */
#include <errno.h>
#include <inttypes.h>
#include <linux/perf_event.h>
#include <sys/ioctl.h>
#include <sys/syscall.h>
#include <unistd.h>

#include "bench_common.h"

static const char usage[] = "usage: pub_cost TOPIC SIZE COUNT ROUNDS   (manager: $LN_MANAGER)\n";

enum { LOOP_MEMCPY, LOOP_WRITE, LOOP_LOAN };

typedef struct counters {
    int fd[2]; /* cycles, instructions; -1 if unavailable */
    const char* why;
} counters;

static int open_counter(uint64_t config)
{
    struct perf_event_attr a;
    memset(&a, 0, sizeof a);
    a.size = sizeof a;
    a.type = PERF_TYPE_HARDWARE;
    a.config = config;
    a.disabled = 1;
    a.exclude_kernel = 1;
    a.exclude_hv = 1;
    return (int)syscall(SYS_perf_event_open, &a, 0, -1, -1, 0);
}

static void open_counters(counters* c)
{
    c->fd[0] = open_counter(PERF_COUNT_HW_CPU_CYCLES);
    c->fd[1] = c->fd[0] < 0 ? -1 : open_counter(PERF_COUNT_HW_INSTRUCTIONS);
    c->why = c->fd[1] < 0 ? strerror(errno) : NULL;
}

static void counters_toggle(const counters* c, unsigned long request)
{
    for (int i = 0; i < 2 && c->fd[1] >= 0; i++) {
        if (request == PERF_EVENT_IOC_ENABLE)
            ioctl(c->fd[i], PERF_EVENT_IOC_RESET, 0);
        ioctl(c->fd[i], request, 0);
    }
}

/* One timed round of `count` publishes of kind `loop`; returns ns per op. */
static double round_ns(int loop, ln_outport* pub, uint8_t* src, uint8_t* dst, size_t size,
                       uint64_t count)
{
    uint64_t t0 = bench_now_ns();
    for (uint64_t i = 0; i < count; i++) {
        int rc = 0;
        memcpy(src, &i, sizeof i);
        if (loop == LOOP_MEMCPY) {
            memcpy(dst, src, size);
            __asm__ volatile("" : : "r"(dst) : "memory"); /* keep the copy */
        } else if (loop == LOOP_WRITE) {
            rc = ln_write(pub, src, size, -1);
        } else {
            void* slot;
            if ((rc = ln_write_loan(pub, &slot, -1)) == 0) {
                memcpy(slot, &i, sizeof i);
                rc = ln_write_commit(pub);
            }
        }
        if (rc < 0)
            bench_fail("publish", rc);
    }
    return (double)(bench_now_ns() - t0) / (double)count;
}

static int cmp_double(const void* a, const void* b)
{
    double x = *(const double*)a, y = *(const double*)b;
    return (x > y) - (x < y);
}

/* Median and min ns/op over `rounds` rounds, plus counters per op, as a JSON object. */
static void measure(const char* label, int loop, ln_outport* pub, uint8_t* src, uint8_t* dst,
                    size_t size, uint64_t count, int rounds, const counters* c, int last)
{
    double ns[64];
    uint64_t cyc = 0, ins = 0;
    round_ns(loop, pub, src, dst, size, count / 10 + 1); /* warm-up */
    for (int r = 0; r < rounds; r++) {
        counters_toggle(c, PERF_EVENT_IOC_ENABLE);
        ns[r] = round_ns(loop, pub, src, dst, size, count);
        counters_toggle(c, PERF_EVENT_IOC_DISABLE);
        uint64_t v[2] = {0, 0};
        for (int i = 0; i < 2 && c->fd[1] >= 0; i++)
            if (read(c->fd[i], &v[i], sizeof v[i]) != (ssize_t)sizeof v[i])
                v[i] = 0;
        cyc += v[0];
        ins += v[1];
    }
    qsort(ns, (size_t)rounds, sizeof ns[0], cmp_double);
    double ops = (double)count * rounds;
    printf("\"%s\": {\"median_ns\": %.2f, \"min_ns\": %.2f, \"max_ns\": %.2f", label,
           ns[rounds / 2], ns[0], ns[rounds - 1]);
    if (c->fd[1] >= 0)
        printf(", \"cycles\": %.1f, \"instructions\": %.1f", (double)cyc / ops, (double)ins / ops);
    printf("}%s", last ? "" : ", ");
}

int main(int argc, char** argv)
{
    if (argc != 5) {
        fputs(usage, stderr);
        return 2;
    }
    const char* topic = argv[1];
    bench_md md = bench_md_for(strtoull(argv[2], NULL, 10));
    uint64_t count = strtoull(argv[3], NULL, 10);
    int rounds = atoi(argv[4]);
    if (rounds < 1 || rounds > 64 || count == 0) {
        fprintf(stderr, "pub_cost: ROUNDS must be 1..64 and COUNT positive\n");
        return 2;
    }
    ln_client* clnt;
    ln_outport* pub;
    ln_inport* sub;
    int rc = ln_client_create(&clnt, "pub_cost", NULL);
    if (rc < 0)
        bench_fail("ln_client_create", rc);
    if ((rc = ln_publish(clnt, &pub, topic, md.name, md.hash, md.size, NULL)) < 0)
        bench_fail("ln_publish", rc);
    uint8_t* src = bench_alloc(md.size);
    uint8_t* dst = bench_alloc(md.size);
    counters c;
    open_counters(&c);
    printf("{\"perf_counters\": %s, ", c.fd[1] >= 0 ? "true" : "false");
    if (c.why)
        printf("\"perf_counters_error\": \"%s\", ", c.why);
    measure("memcpy", LOOP_MEMCPY, pub, src, dst, md.size, count, rounds, &c, 0);
    measure("write_no_subscriber", LOOP_WRITE, pub, src, dst, md.size, count, rounds, &c, 0);
    measure("loan_no_subscriber", LOOP_LOAN, pub, src, dst, md.size, count, rounds, &c, 0);
    /* A subscriber that exists but never reads, so never sleeps: the usual case. */
    if ((rc = ln_subscribe(clnt, &sub, topic, md.name, md.hash, md.size, NULL)) < 0)
        bench_fail("ln_subscribe", rc);
    measure("write_idle_subscriber", LOOP_WRITE, pub, src, dst, md.size, count, rounds, &c, 1);
    printf("}\n");
    ln_client_destroy(clnt);
    return 0;
}
