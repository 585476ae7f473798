/* rt_futex.c — the floor of bench/realtime: the same periodic ping-pong as rt_ln (rt_common.h)
 * over a bare shared mapping (/dev/shm/ln_rtbench_NAME, made by pong, removed by ping) and two
 * futex words, waking only a sleeper, with one copy in and one out per message: what any
 * shared-memory transport has to pay for a wake-up across processes. */
#include <fcntl.h>
#include <linux/futex.h>
#include <stdatomic.h>
#include <sys/syscall.h>
#include <unistd.h>

#include "rt_common.h"

static const char usage[] = "usage: rt_futex ping NAME pingpong|control RATE_HZ COUNT WARMUP OUT\n"
                            "       rt_futex pong NAME pingpong|control TOTAL WARMUP\n";

/* One direction: a sequence word to sleep on, a count of sleepers, and the payload. */
typedef struct channel {
    _Alignas(64) _Atomic uint32_t seq;
    _Atomic uint32_t waiters;
    _Alignas(64) unsigned char payload[RT_MAX_SIZE];
} channel;

typedef struct side {
    channel* out;
    channel* in;
    uint32_t seen;
    unsigned char buf[RT_MAX_SIZE];
} side;

static void futex(_Atomic uint32_t* word, int op, uint32_t value)
{
    syscall(SYS_futex, (uint32_t*)word, op, value, NULL, NULL, 0);
}

static void send_one(void* ctx, uint64_t counter, size_t size)
{
    side* s = ctx;
    memcpy(s->buf, &counter, sizeof counter);
    memcpy(s->out->payload, s->buf, size);
    atomic_fetch_add(&s->out->seq, 1); /* seq_cst, paired with the sleeper's re-check */
    if (atomic_load(&s->out->waiters) > 0)
        futex(&s->out->seq, FUTEX_WAKE, 1);
}

static uint64_t receive_one(void* ctx, size_t size)
{
    side* s = ctx;
    channel* ch = s->in;
    while (atomic_load_explicit(&ch->seq, memory_order_acquire) == s->seen) {
        atomic_fetch_add(&ch->waiters, 1);
        if (atomic_load(&ch->seq) == s->seen)
            futex(&ch->seq, FUTEX_WAIT, s->seen);
        atomic_fetch_sub(&ch->waiters, 1);
    }
    s->seen += 1;
    memcpy(s->buf, ch->payload, size);
    uint64_t counter;
    memcpy(&counter, s->buf, sizeof counter);
    return counter;
}

static channel* map_channels(const char* path, int create)
{
    int fd = shm_open(path, create ? O_RDWR | O_CREAT | O_EXCL : O_RDWR, 0600);
    if (fd < 0 || (create && ftruncate(fd, 2 * sizeof(channel)) != 0)) {
        perror(path);
        exit(2);
    }
    void* p = mmap(NULL, 2 * sizeof(channel), PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
    close(fd);
    if (p == MAP_FAILED) {
        perror("rt_futex: mmap");
        exit(2);
    }
    return p; /* ftruncate zeroed it: both sequences start at 0 */
}

int main(int argc, char** argv)
{
    int ping = argc == 8 && strcmp(argv[1], "ping") == 0;
    if (!ping && !(argc == 6 && strcmp(argv[1], "pong") == 0)) {
        fputs(usage, stderr);
        return 2;
    }
    rt_shape shape = rt_shape_of(argv[3]);
    char path[256];
    snprintf(path, sizeof path, "/ln_rtbench_%s", argv[2]);
    channel* ch = map_channels(path, !ping);
    static side s; /* the buffer stays off the stack */
    s.out = ping ? &ch[0] : &ch[1];
    s.in = ping ? &ch[1] : &ch[0];
    rt_ops ops = {send_one, receive_one};
    if (!ping)
        return rt_pong(&ops, &s, &shape, strtoull(argv[4], NULL, 10), strtoull(argv[5], NULL, 10));
    int rc = rt_ping(&ops, &s, &shape, atof(argv[4]), strtoull(argv[5], NULL, 10),
                     strtoull(argv[6], NULL, 10), argv[7]);
    shm_unlink(path);
    return rc;
}
