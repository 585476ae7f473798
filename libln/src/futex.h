/* futex.h — wait/wake on a 32-bit word in shared memory (process-shared futexes).
 * Used by topic rings so that a reader can sleep until a publisher commits, and a publisher
 * pays for a system call only when somebody actually sleeps. */
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

/* Sleep while *word == expected, at most `rel` (NULL: forever).  Returns 0 when woken or when
 * the value already differed (EAGAIN), ETIMEDOUT or EINTR otherwise. */
static inline int ln_futex_wait(_Atomic uint32_t* word, uint32_t expected,
                                const struct timespec* rel)
{
    long r = syscall(SYS_futex, (uint32_t*)word, FUTEX_WAIT, expected, rel, NULL, 0);
    if (r == 0 || errno == EAGAIN)
        return 0;
    return errno;
}

static inline void ln_futex_wake_all(_Atomic uint32_t* word)
{
    syscall(SYS_futex, (uint32_t*)word, FUTEX_WAKE, INT_MAX, NULL, NULL, 0);
}

#endif /* LN_FUTEX_H */
