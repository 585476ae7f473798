/* futex.h — sleep and wake on a 32-bit word in shared memory (process-shared futexes).
 * The top bit of a futex word announces sleepers: a waker makes a system call only when it is
 * set, and a sleeper that dies (SIGKILL) costs at most one extra wake, never one per publish. */
#ifndef LN_FUTEX_H
#define LN_FUTEX_H

#include <errno.h>
#include <limits.h>
#include <linux/futex.h>
#include <stdatomic.h>
#include <stdint.h>
#include <sys/syscall.h>
#include <time.h>
#include <unistd.h>

#define LN_FUTEX_SLEEPERS 0x80000000u

/* Sleep while *word == expected, at most `rel` (NULL: forever).  Returns 0 when woken or when
 * the value already differed, ETIMEDOUT or EINTR otherwise. */
static inline int ln_futex_wait(_Atomic uint32_t* word, uint32_t expected,
                                const struct timespec* rel)
{
    long r = syscall(SYS_futex, (uint32_t*)word, FUTEX_WAIT, expected, rel, NULL, 0);
    if (r == 0 || errno == EAGAIN)
        return 0;
    return errno;
}

/* Sleeper, before re-checking its condition: set the sleepers bit (seq_cst) and get the value
 * to pass to ln_futex_wait. */
static inline uint32_t ln_futex_announce(_Atomic uint32_t* word)
{
    return atomic_fetch_or_explicit(word, LN_FUTEX_SLEEPERS, memory_order_seq_cst) |
           LN_FUTEX_SLEEPERS;
}

/* Change the word (so no sleeper can miss the change), clear the sleepers bit, wake all. */
static inline void ln_futex_bump_wake(_Atomic uint32_t* word)
{
    uint32_t v = atomic_load_explicit(word, memory_order_seq_cst);
    while (!atomic_compare_exchange_weak_explicit(
        word, &v, ((v & ~LN_FUTEX_SLEEPERS) + 1) & ~LN_FUTEX_SLEEPERS, memory_order_seq_cst,
        memory_order_seq_cst))
        ;
    syscall(SYS_futex, (uint32_t*)word, FUTEX_WAKE, INT_MAX, NULL, NULL, 0);
}

/* Waker, after publishing its change (seq_cst): wake only if somebody announced sleeping. */
static inline void ln_futex_wake_sleepers(_Atomic uint32_t* word)
{
    if (atomic_load_explicit(word, memory_order_seq_cst) & LN_FUTEX_SLEEPERS)
        ln_futex_bump_wake(word);
}

#endif /* LN_FUTEX_H */
