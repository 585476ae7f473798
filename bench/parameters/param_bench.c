/* param_bench.c — what a parameter block costs a control loop (bench/parameters, driven by
 * bench_parameters.py), in one process against the manager of $LN_MANAGER.  The block holds
 * the inputs of a typical joint controller (kp, kd: double[7], limits: float[2], mode: int32,
 * cycle: uint64; 132 bytes copied per update) and a gain without input.  Measures:
 *   update: ns per ln_parameter_block_update() with no pending change, over ROUNDS rounds of
 *           N calls, beside the floor of the same 5 memcpy of the same bytes (what the loop
 *           would do anyway to copy inputs to outputs);
 *   syscalls: whether update() makes any system call: a child process runs it (a pending
 *           change first, then N calls) under a seccomp filter that kills it on any call
 *           but exit (x86-64 only);
 *   latency: from the moment a setter thread calls the block's service (a set of the gain)
 *           until the loop's update() returns the change, for a loop that spins and for a
 *           1 kHz loop on absolute deadlines; and the round trip of that set call.
 * Prints one JSON object.  Usage: param_bench [N] [ROUNDS] [SETS] */
#define _GNU_SOURCE 1

#include <inttypes.h>
#include <pthread.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <ln/ln.h>

#include "param_messages.h"

static uint64_t now_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000000000u + (uint64_t)ts.tv_nsec;
}

static void fail(const char* what, int rc)
{
    fprintf(stderr, "param_bench: %s: %s (%s)\n", what, ln_error_name(rc), ln_last_error());
    exit(1);
}

struct vars {
    double kp_in[7], kp[7], kd_in[7], kd[7];
    float limits_in[2], limits[2];
    int32_t mode_in, mode;
    uint64_t cycle_in, cycle;
    double gain;
};

static struct vars v;
static ln_parameter_block* blk;

static int cmp_u64(const void* a, const void* b)
{
    uint64_t x = *(const uint64_t*)a, y = *(const uint64_t*)b;
    return x < y ? -1 : x > y;
}

/* The baseline: the copies update() makes, as a loop would write them itself. */
static void __attribute__((noinline)) copy_floor(struct vars* w)
{
    memcpy(w->kp, w->kp_in, sizeof w->kp);
    memcpy(w->kd, w->kd_in, sizeof w->kd);
    memcpy(w->limits, w->limits_in, sizeof w->limits);
    memcpy(&w->mode, &w->mode_in, sizeof w->mode);
    memcpy(&w->cycle, &w->cycle_in, sizeof w->cycle);
    __asm__ volatile("" ::: "memory");
}

static void print_stats(const char* name, uint64_t* x, size_t n, int last)
{
    qsort(x, n, sizeof *x, cmp_u64);
    printf("\"%s\": {\"n\": %zu, \"min\": %" PRIu64 ", \"p50\": %" PRIu64 ", \"p90\": %" PRIu64
           ", \"p99\": %" PRIu64 ", \"max\": %" PRIu64 "}%s\n",
           name, n, x[0], x[n / 2], x[n * 9 / 10], x[n * 99 / 100], x[n - 1], last ? "" : ",");
}

/* ---- update() cost ---- */

static void update_cost(long n, int rounds)
{
    double best_update = 1e9, best_floor = 1e9;
    double* ups = calloc((size_t)rounds, sizeof *ups);
    double* floors = calloc((size_t)rounds, sizeof *floors);
    for (int r = 0; r < rounds; r++) {
        uint64_t t0 = now_ns();
        for (long i = 0; i < n; i++)
            if (ln_parameter_block_update(blk) != 0)
                fail("update found a change", LN_EINVAL);
        uint64_t t1 = now_ns();
        for (long i = 0; i < n; i++)
            copy_floor(&v);
        uint64_t t2 = now_ns();
        ups[r] = (double)(t1 - t0) / (double)n;
        floors[r] = (double)(t2 - t1) / (double)n;
        if (ups[r] < best_update)
            best_update = ups[r];
        if (floors[r] < best_floor)
            best_floor = floors[r];
    }
    printf("\"update_ns\": [");
    for (int r = 0; r < rounds; r++)
        printf("%s%.3f", r ? ", " : "", ups[r]);
    printf("],\n\"floor_ns\": [");
    for (int r = 0; r < rounds; r++)
        printf("%s%.3f", r ? ", " : "", floors[r]);
    printf("],\n\"update_calls_per_round\": %ld,\n", n);
    free(ups);
    free(floors);
}

/* ---- system calls ---- */

#if defined(__x86_64__)
#include <linux/audit.h>
#include <linux/filter.h>
#include <linux/seccomp.h>
#include <stddef.h>
#include <sys/prctl.h>
#include <sys/syscall.h>

static int forbid_syscalls(void)
{
    struct sock_filter filter[] = {
        BPF_STMT(BPF_LD | BPF_W | BPF_ABS, offsetof(struct seccomp_data, arch)),
        BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, AUDIT_ARCH_X86_64, 1, 0),
        BPF_STMT(BPF_RET | BPF_K, SECCOMP_RET_KILL_PROCESS),
        BPF_STMT(BPF_LD | BPF_W | BPF_ABS, offsetof(struct seccomp_data, nr)),
        BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, __NR_exit_group, 2, 0),
        BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, __NR_exit, 1, 0),
        BPF_STMT(BPF_RET | BPF_K, SECCOMP_RET_KILL_PROCESS),
        BPF_STMT(BPF_RET | BPF_K, SECCOMP_RET_ALLOW),
    };
    struct sock_fprog prog = {.len = sizeof filter / sizeof filter[0], .filter = filter};
    if (prctl(PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0) != 0)
        return -1;
    return prctl(PR_SET_SECCOMP, SECCOMP_MODE_FILTER, &prog);
}

/* "none" if the child ran update() without a system call, else what happened. */
static const char* syscall_check(long n)
{
    fflush(NULL);
    pid_t child = fork();
    if (child == 0) {
        if (forbid_syscalls() != 0)
            syscall(SYS_exit_group, 3);
        int changed = 0;
        for (long i = 0; i < n; i++)
            changed += ln_parameter_block_update(blk);
        syscall(SYS_exit_group, changed == 1 ? 0 : 4); /* the pending change, once */
    }
    int status = 0;
    if (waitpid(child, &status, 0) != child)
        return "waitpid failed";
    if (WIFSIGNALED(status) && WTERMSIG(status) == SIGSYS)
        return "a system call (killed by SIGSYS)";
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
        return "the child failed";
    return "none";
}
#else
static const char* syscall_check(long n)
{
    (void)n;
    return "not checked (x86-64 only)";
}
#endif

/* ---- latency ---- */

static atomic_int loop_stop;
static atomic_uint_fast64_t seen_ns; /* when the loop's update() returned the last change */
static long loop_period_ns;          /* 0: spin */

static void* loop(void* arg)
{
    (void)arg;
    struct timespec next;
    clock_gettime(CLOCK_MONOTONIC, &next);
    while (!atomic_load(&loop_stop)) {
        v.cycle_in++;
        if (ln_parameter_block_update(blk) > 0)
            atomic_store(&seen_ns, now_ns());
        if (loop_period_ns > 0) {
            next.tv_nsec += loop_period_ns;
            while (next.tv_nsec >= 1000000000L) {
                next.tv_nsec -= 1000000000L;
                next.tv_sec++;
            }
            clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, NULL);
        }
    }
    return NULL;
}

static void latency(ln_client* clnt, const char* name, long period_ns, int sets, int first,
                    int last)
{
    ln_service* svc;
    int rc = ln_get_service(clnt, &svc, ln_parameter_block_service_name(blk),
                            LN_PARAMETERS_QUERY_SERVICE);
    if (rc < 0)
        fail("ln_get_service", rc);
    loop_period_ns = period_ns;
    atomic_store(&loop_stop, 0);
    pthread_t t;
    pthread_create(&t, NULL, loop, NULL);
    uint64_t* visible = calloc((size_t)sets, sizeof *visible);
    uint64_t* call = calloc((size_t)sets, sizeof *call);
    int warm = sets / 10 + 1;
    for (int k = -warm; k < sets; k++) {
        char value[32];
        snprintf(value, sizeof value, "%d", first + k + warm);
        ln_parameters_query_request_t req = {.op_len = 3,
                                             .op = (char*)"set",
                                             .name_len = 4,
                                             .name = (char*)"gain",
                                             .value_len = (uint32_t)strlen(value),
                                             .value = value};
        ln_parameters_query_response_t resp;
        uint64_t before = atomic_load(&seen_ns);
        uint64_t t0 = now_ns();
        if ((rc = ln_service_call(svc, &req, &resp, 5.0)) < 0)
            fail("ln_service_call", rc);
        uint64_t t1 = now_ns();
        if (resp.status != 0) {
            fprintf(stderr, "param_bench: set refused: %.*s\n", (int)resp.reason_len, resp.reason);
            exit(1);
        }
        uint64_t seen;
        while ((seen = atomic_load(&seen_ns)) == before) { /* the loop takes it soon */
            struct timespec poll = {0, 20000};             /* the loop stamps it: no need to spin */
            nanosleep(&poll, NULL);
        }
        if (k >= 0) {
            visible[k] = seen - t0;
            call[k] = t1 - t0;
        }
        struct timespec pause = {0, 200000}; /* sets spaced, as a person or script would */
        nanosleep(&pause, NULL);
    }
    atomic_store(&loop_stop, 1);
    pthread_join(t, NULL);
    ln_service_release(svc);
    char key[64];
    snprintf(key, sizeof key, "%s_visible_ns", name);
    print_stats(key, visible, (size_t)sets, 0);
    snprintf(key, sizeof key, "%s_call_ns", name);
    print_stats(key, call, (size_t)sets, last);
    free(visible);
    free(call);
}

int main(int argc, char** argv)
{
    long n = argc > 1 ? atol(argv[1]) : 10000000;
    int rounds = argc > 2 ? atoi(argv[2]) : 7;
    int sets = argc > 3 ? atoi(argv[3]) : 1000;
    ln_client* clnt;
    int rc = ln_client_create(&clnt, "param_bench", NULL);
    if (rc < 0)
        fail("ln_client_create", rc);
    if ((rc = ln_parameter_block_create(clnt, &blk, "bench")) < 0)
        fail("ln_parameter_block_create", rc);
    const ln_parameter_desc d[] = {
        {.name = "kp",
         .type = "double",
         .count = 7,
         .input = v.kp_in,
         .output = v.kp,
         .flags = LN_PARAMETER_MIN | LN_PARAMETER_MAX,
         .min = 0,
         .max = 1000},
        {.name = "kd", .type = "double", .count = 7, .input = v.kd_in, .output = v.kd},
        {.name = "limits", .type = "float", .count = 2, .input = v.limits_in, .output = v.limits},
        {.name = "mode", .type = "int32_t", .input = &v.mode_in, .output = &v.mode},
        {.name = "cycle", .type = "uint64_t", .input = &v.cycle_in, .output = &v.cycle},
        {.name = "gain", .type = "double", .output = &v.gain},
    };
    for (size_t i = 0; i < sizeof d / sizeof d[0]; i++)
        if ((rc = ln_parameter_block_add(blk, &d[i])) < 0)
            fail("ln_parameter_block_add", rc);
    if ((rc = ln_parameter_block_register(blk)) < 0)
        fail("ln_parameter_block_register", rc);
    ln_parameter_block_update(blk);

    printf("{\n\"copied_bytes\": %zu,\n",
           sizeof v.kp + sizeof v.kd + sizeof v.limits + sizeof v.mode + sizeof v.cycle);
    update_cost(n, rounds);
    /* a change waits for the child's first update */
    ln_service* svc;
    if ((rc = ln_get_service(clnt, &svc, ln_parameter_block_service_name(blk),
                             LN_PARAMETERS_QUERY_SERVICE)) < 0)
        fail("ln_get_service", rc);
    ln_parameters_query_request_t req = {.op_len = 3,
                                         .op = (char*)"set",
                                         .name_len = 4,
                                         .name = (char*)"gain",
                                         .value_len = 1,
                                         .value = (char*)"1"};
    ln_parameters_query_response_t resp;
    if ((rc = ln_service_call(svc, &req, &resp, 5.0)) < 0 || resp.status != 0)
        fail("set before the system call check", rc < 0 ? rc : LN_EINVAL);
    ln_service_release(svc);
    printf("\"syscalls\": \"%s\",\n\"syscall_check_updates\": %ld,\n", syscall_check(n / 10),
           n / 10);
    ln_parameter_block_update(blk); /* take it here too */
    latency(clnt, "spin", 0, sets, 10, 0);
    latency(clnt, "khz", 1000000, sets / 2, 100000, 1);
    printf("}\n");
    ln_parameter_block_destroy(blk);
    ln_client_destroy(clnt);
    return 0;
}
