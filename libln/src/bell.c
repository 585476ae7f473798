/* bell.c — ringing a waitset's bell (bell.h): one process-wide unbound datagram socket sends
 * every bell of this process; the ring side keeps who wants one in its reader slots. */
#include "bell.h"

#include <errno.h>
#include <stdatomic.h>
#include <stddef.h>
#include <string.h>
#include <unistd.h>

static _Atomic int sender = -1;

static int sender_fd(void)
{
    int fd = atomic_load_explicit(&sender, memory_order_acquire);
    if (fd >= 0)
        return fd;
    int made = socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
    if (made < 0)
        return -1;
    int expected = -1;
    if (!atomic_compare_exchange_strong(&sender, &expected, made)) {
        close(made); /* another thread made one first */
        return expected;
    }
    return made;
}

socklen_t ln_bell_address(uint64_t id, struct sockaddr_un* addr)
{
    static const char hex[] = "0123456789abcdef";
    static const char prefix[] = "ln.bell.";
    memset(addr, 0, sizeof *addr);
    addr->sun_family = AF_UNIX;
    char* p = addr->sun_path + 1; /* sun_path[0] = 0: the abstract namespace */
    memcpy(p, prefix, sizeof prefix - 1);
    p += sizeof prefix - 1;
    for (int shift = 60; shift >= 0; shift -= 4)
        *p++ = hex[(id >> shift) & 0xf];
    return (socklen_t)(offsetof(struct sockaddr_un, sun_path) + (size_t)(p - addr->sun_path));
}

void ln_bell_ring(uint64_t id, uint32_t tag)
{
    int fd = sender_fd();
    if (fd < 0 || id == 0)
        return;
    struct sockaddr_un addr;
    socklen_t len = ln_bell_address(id, &addr);
    int saved = errno; /* callers are deep in write paths that report errno of their own */
    /* EAGAIN: the bell's queue is full, and a waitset that finds it full looks at everything
     * (waitset.c); ECONNREFUSED: the waitset is gone. */
    (void)sendto(fd, &tag, sizeof tag, MSG_DONTWAIT | MSG_NOSIGNAL, (struct sockaddr*)&addr, len);
    errno = saved;
}

void ln_ring_ring_bells(ln_ring_header* h, int all)
{
    uint64_t mask = atomic_load_explicit(&h->bell_readers, memory_order_seq_cst);
    while (mask) {
        uint32_t i = (uint32_t)__builtin_ctzll(mask);
        mask &= mask - 1;
        ln_ring_reader* r = &h->readers[i];
        /* rung already and not looked at yet: a plain load, no locked exchange on the line
         * the waitset writes (its store of 0 precedes its look at write_seq, seq_cst) */
        if (!all && atomic_load_explicit(&r->bell_pending, memory_order_seq_cst))
            continue;
        uint32_t was = atomic_exchange_explicit(&r->bell_pending, 1, memory_order_seq_cst);
        if (was == 0 || all)
            ln_bell_ring(atomic_load_explicit(&r->bell, memory_order_acquire),
                         atomic_load_explicit(&r->bell_tag, memory_order_relaxed));
    }
}

void ln_ring_set_bell(ln_ring_header* h, uint32_t reader, uint64_t id, uint32_t tag)
{
    if (reader >= LN_RING_MAX_READERS)
        return;
    ln_ring_reader* r = &h->readers[reader];
    uint64_t bit = (uint64_t)1 << reader;
    if (id == 0) {
        atomic_fetch_and_explicit(&h->bell_readers, ~bit, memory_order_seq_cst);
        atomic_store_explicit(&r->bell, 0, memory_order_release);
        return;
    }
    atomic_store_explicit(&r->bell_tag, tag, memory_order_relaxed);
    atomic_store_explicit(&r->bell, id, memory_order_release);
    atomic_store_explicit(&r->bell_pending, 0, memory_order_seq_cst);
    atomic_fetch_or_explicit(&h->bell_readers, bit, memory_order_seq_cst);
}

void ln_ring_clear_bell(ln_ring_header* h, uint32_t reader) { ln_ring_set_bell(h, reader, 0, 0); }
