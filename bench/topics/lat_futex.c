/* lat_futex.c — the floor under lat_ln: the same ping-pong with the same four payload copies
 * per round trip, over a bare shared mapping and two futex words (waking only a sleeper, as
 * topic rings do), between this process (ping) and a forked pong. */
#include <linux/futex.h>
#include <sched.h>
#include <signal.h>
#include <stdatomic.h>
#include <sys/mman.h>
#include <sys/prctl.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include "bench_common.h"

static const char usage[] =
    "usage: lat_futex SIZE COUNT WARMUP OUT [PONG_CPU]   COUNT round trips (ns) to OUT\n";

/* One direction: a sequence word to sleep on, a count of sleepers, and the payload. */
typedef struct channel {
    _Alignas(64) _Atomic uint32_t seq;
    _Atomic uint32_t waiters;
    uint8_t* payload;
} channel;

static void futex(_Atomic uint32_t* word, int op, uint32_t value)
{
    syscall(SYS_futex, (uint32_t*)word, op, value, NULL, NULL, 0);
}

static void send_one(channel* ch, const void* src, size_t size)
{
    memcpy(ch->payload, src, size);
    atomic_fetch_add(&ch->seq, 1); /* seq_cst, paired with the sleeper's re-check */
    if (atomic_load(&ch->waiters) > 0)
        futex(&ch->seq, FUTEX_WAKE, 1);
}

/* Wait until ch->seq moves past *seen, then copy the payload out. */
static void receive_one(channel* ch, uint32_t* seen, void* dst, size_t size)
{
    while (atomic_load_explicit(&ch->seq, memory_order_acquire) == *seen) {
        atomic_fetch_add(&ch->waiters, 1);
        if (atomic_load(&ch->seq) == *seen)
            futex(&ch->seq, FUTEX_WAIT, *seen);
        atomic_fetch_sub(&ch->waiters, 1);
    }
    *seen += 1;
    memcpy(dst, ch->payload, size);
}

int main(int argc, char** argv)
{
    if (argc != 5 && argc != 6) {
        fputs(usage, stderr);
        return 2;
    }
    size_t size = strtoull(argv[1], NULL, 10);
    uint64_t count = strtoull(argv[2], NULL, 10), warmup = strtoull(argv[3], NULL, 10);
    size_t stride = (size + 63) / 64 * 64;
    size_t len = 2 * sizeof(channel) + 2 * stride;
    uint8_t* shared = mmap(NULL, len, PROT_READ | PROT_WRITE, MAP_SHARED | MAP_ANONYMOUS, -1, 0);
    uint64_t* rtt = calloc(count ? count : 1, sizeof(*rtt));
    if (shared == MAP_FAILED || !rtt) {
        perror("lat_futex: mmap");
        return 2;
    }
    memset(shared, 0, len);
    channel* to_pong = (channel*)shared;
    channel* to_ping = to_pong + 1;
    to_pong->payload = shared + 2 * sizeof(channel);
    to_ping->payload = to_pong->payload + stride;
    uint8_t* buf = bench_alloc(size);
    uint32_t seen = 0;
    pid_t pong = fork();
    if (pong < 0) {
        perror("lat_futex: fork");
        return 2;
    }
    if (pong == 0) {
        prctl(PR_SET_PDEATHSIG, SIGKILL);
        if (argc == 6) {
            cpu_set_t set;
            CPU_ZERO(&set);
            CPU_SET(atoi(argv[5]), &set);
            if (sched_setaffinity(0, sizeof set, &set) != 0) {
                perror("lat_futex: sched_setaffinity");
                _exit(2);
            }
        }
        for (uint64_t i = 0; i < warmup + count; i++) {
            receive_one(to_pong, &seen, buf, size);
            send_one(to_ping, buf, size);
        }
        _exit(0);
    }
    uint8_t* reply = bench_alloc(size);
    for (uint64_t i = 0; i < warmup + count; i++) {
        uint64_t t0 = bench_now_ns(), got;
        memcpy(buf, &i, sizeof i);
        send_one(to_pong, buf, size);
        receive_one(to_ping, &seen, reply, size);
        uint64_t t1 = bench_now_ns();
        memcpy(&got, reply, sizeof got);
        if (got != i) {
            fprintf(stderr, "lat_futex: round trip %llu came back as %llu\n", (unsigned long long)i,
                    (unsigned long long)got);
            return 1;
        }
        if (i >= warmup)
            rtt[i - warmup] = t1 - t0;
    }
    int status = 0;
    waitpid(pong, &status, 0);
    bench_write_samples(argv[4], rtt, count);
    return WIFEXITED(status) && WEXITSTATUS(status) == 0 ? 0 : 1;
}
