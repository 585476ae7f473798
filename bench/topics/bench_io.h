/* bench_io.h — what the raw socket baselines (bench/services/svc_echo_raw.c,
 * bench/network/pingpong.c) share: giving up on a failed system call, and reading or
 * writing a whole message on a stream socket.  Messages name the program. */
#ifndef BENCH_IO_H
#define BENCH_IO_H

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static inline void bench_die(const char* what)
{
    fprintf(stderr, "%s: %s: %s\n", program_invocation_short_name, what, strerror(errno));
    exit(2);
}

/* Read exactly `len` bytes; 0 on EOF before the first byte, 1 when done. */
static inline int bench_read_full(int fd, void* buf, size_t len)
{
    size_t got = 0;
    while (got < len) {
        ssize_t n = read(fd, (char*)buf + got, len - got);
        if (n < 0 && errno == EINTR)
            continue;
        if (n < 0)
            bench_die("read");
        if (n == 0) {
            if (got == 0)
                return 0;
            fprintf(stderr, "%s: EOF inside a message\n", program_invocation_short_name);
            exit(2);
        }
        got += (size_t)n;
    }
    return 1;
}

static inline void bench_write_full(int fd, const void* buf, size_t len)
{
    size_t sent = 0;
    while (sent < len) {
        ssize_t n = write(fd, (const char*)buf + sent, len - sent);
        if (n < 0 && errno == EINTR)
            continue;
        if (n < 0)
            bench_die("write");
        sent += (size_t)n;
    }
}

#endif /* BENCH_IO_H */
