/* net.c — TCP to the manager on a non-blocking socket: every wait is a poll() bounded by an
 * absolute CLOCK_MONOTONIC deadline, so a stalled or dead manager costs at most the client's
 * timeout, and EINTR never cuts a transfer short. */
#include "net.h"

#include <errno.h>
#include <limits.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

/* Longest deadline honoured (about 31 years); keeps tv_sec arithmetic far from overflow. */
#define MAX_TIMEOUT 1e9

const struct timespec* ln_net_deadline(struct timespec* ts, double timeout)
{
    if (!(timeout >= 0))
        return NULL;
    if (timeout > MAX_TIMEOUT)
        timeout = MAX_TIMEOUT;
    clock_gettime(CLOCK_MONOTONIC, ts);
    time_t sec = (time_t)timeout;
    long nsec = ts->tv_nsec + (long)((timeout - (double)sec) * 1e9);
    ts->tv_sec += sec + nsec / 1000000000L;
    ts->tv_nsec = nsec % 1000000000L;
    return ts;
}

/* Milliseconds left until the deadline, rounded up so poll() never wakes early; -1 for no
 * deadline, 0 once it has passed. */
static int remaining_ms(const struct timespec* deadline)
{
    if (deadline == NULL)
        return -1;
    struct timespec now;
    clock_gettime(CLOCK_MONOTONIC, &now);
    long long ns = (long long)(deadline->tv_sec - now.tv_sec) * 1000000000LL +
                   (deadline->tv_nsec - now.tv_nsec);
    if (ns <= 0)
        return 0;
    long long ms = (ns + 999999) / 1000000;
    return ms > INT_MAX ? INT_MAX : (int)ms;
}

/* 0 when fd is ready for `events` (or has an error or hang-up for the next call to report),
 * ETIMEDOUT at the deadline, ECANCELED once cancel_fd (if >= 0) is readable, else an errno
 * value. */
static int wait_fd(int fd, short events, const struct timespec* deadline, int cancel_fd)
{
    for (;;) {
        struct pollfd pfd[2] = {{.fd = fd, .events = events, .revents = 0},
                                {.fd = cancel_fd, .events = POLLIN, .revents = 0}};
        int n = poll(pfd, cancel_fd >= 0 ? 2 : 1, remaining_ms(deadline));
        if (n > 0 && pfd[1].revents)
            return ECANCELED;
        if (n > 0)
            return pfd[0].revents & POLLNVAL ? EBADF : 0;
        if (n == 0)
            return ETIMEDOUT;
        if (errno != EINTR)
            return errno;
    }
}

int ln_net_resolve(const char* host, const char* port, struct addrinfo** out)
{
    struct addrinfo hints;
    memset(&hints, 0, sizeof hints);
    hints.ai_family = AF_UNSPEC;
    hints.ai_socktype = SOCK_STREAM;
    hints.ai_flags = AI_NUMERICSERV;
    return getaddrinfo(host, port, &hints, out);
}

/* One connection attempt; 0 with *fd or an errno value. */
static int connect_one(const struct addrinfo* ai, const struct timespec* deadline, int cancel_fd,
                       int* fd)
{
    int s = socket(ai->ai_family, ai->ai_socktype | SOCK_NONBLOCK | SOCK_CLOEXEC, ai->ai_protocol);
    if (s < 0)
        return errno;
    int err = 0;
    if (connect(s, ai->ai_addr, ai->ai_addrlen) != 0) {
        /* EINTR: the connection goes on in the background, exactly as for EINPROGRESS. */
        if (errno != EINPROGRESS && errno != EINTR) {
            err = errno;
            goto fail;
        }
        err = wait_fd(s, POLLOUT, deadline, cancel_fd);
        if (err != 0)
            goto fail;
        socklen_t len = sizeof err;
        if (getsockopt(s, SOL_SOCKET, SO_ERROR, &err, &len) != 0)
            err = errno;
        if (err != 0)
            goto fail;
    }
    /* Requests are small and answered one at a time: Nagle would only add latency. */
    int one = 1;
    if (setsockopt(s, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one) != 0) {
        err = errno;
        goto fail;
    }
    *fd = s;
    return 0;

fail:
    close(s);
    return err;
}

int ln_net_connect(const struct addrinfo* ai, const struct timespec* deadline, int cancel_fd,
                   int* fd)
{
    int err = EADDRNOTAVAIL; /* only if the list is empty, which getaddrinfo never returns */
    for (; ai != NULL; ai = ai->ai_next) {
        err = connect_one(ai, deadline, cancel_fd, fd);
        if (err == 0 || err == ETIMEDOUT || err == ECANCELED)
            break;
    }
    return err;
}

int ln_net_write_all(int fd, const void* buf, size_t len, const struct timespec* deadline,
                     int cancel_fd)
{
    const char* p = buf;
    while (len > 0) {
        ssize_t n = send(fd, p, len, MSG_NOSIGNAL);
        if (n >= 0) {
            p += n;
            len -= (size_t)n;
        } else if (errno == EAGAIN || errno == EWOULDBLOCK) {
            int err = wait_fd(fd, POLLOUT, deadline, cancel_fd);
            if (err != 0)
                return err;
        } else if (errno != EINTR) {
            return errno;
        }
    }
    return 0;
}

int ln_net_read_all(int fd, void* buf, size_t len, const struct timespec* deadline, int cancel_fd)
{
    char* p = buf;
    while (len > 0) {
        ssize_t n = recv(fd, p, len, 0);
        if (n > 0) {
            p += n;
            len -= (size_t)n;
        } else if (n == 0) {
            return LN_NET_EOF;
        } else if (errno == EAGAIN || errno == EWOULDBLOCK) {
            int err = wait_fd(fd, POLLIN, deadline, cancel_fd);
            if (err != 0)
                return err;
        } else if (errno != EINTR) {
            return errno;
        }
    }
    return 0;
}

int ln_net_wait_readable(int fd, const struct timespec* deadline, int cancel_fd)
{
    return wait_fd(fd, POLLIN, deadline, cancel_fd);
}
