/* pull_udp.c — POSIX glue for the pull consumer: a UDP socket connected to the producer, the
 * send callback, CLOCK_MONOTONIC in ms and a blocking poll() loop that feeds one subscription
 * until a stop flag is set.  Outside the portable core on purpose. */
#include <errno.h>
#include <netdb.h>
#include <poll.h>
#include <stdio.h>
#include <string.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include "ln/pull_udp.h"

LN_NDN_EXPORT int ln_pull_udp_open(const char* host, uint16_t port)
{
    struct addrinfo hints, *list = NULL, *ai;
    char service[8];
    int fd = -1, err = 0;
    memset(&hints, 0, sizeof hints);
    hints.ai_family = AF_UNSPEC;
    hints.ai_socktype = SOCK_DGRAM;
    snprintf(service, sizeof service, "%u", (unsigned)port);
    if (!host || port == 0) {
        errno = EINVAL;
        return -1;
    }
    if (getaddrinfo(host, service, &hints, &list) != 0) {
        errno = EHOSTUNREACH;
        return -1;
    }
    for (ai = list; ai; ai = ai->ai_next) {
        fd = socket(ai->ai_family, ai->ai_socktype, ai->ai_protocol);
        if (fd < 0) {
            err = errno;
            continue;
        }
        if (connect(fd, ai->ai_addr, ai->ai_addrlen) == 0)
            break;
        err = errno;
        close(fd);
        fd = -1;
    }
    freeaddrinfo(list);
    if (fd < 0)
        errno = err ? err : EHOSTUNREACH;
    return fd;
}

LN_NDN_EXPORT void ln_pull_udp_send(void* user, const uint8_t* packet, size_t size)
{
    /* a lost or refused datagram is a timeout for DIT, so the result is not needed */
    (void)!send(*(const int*)user, packet, size, 0);
}

LN_NDN_EXPORT uint32_t ln_pull_udp_now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint32_t)((uint64_t)ts.tv_sec * 1000u + (uint64_t)ts.tv_nsec / 1000000u);
}

LN_NDN_EXPORT int ln_pull_udp_run(ln_pull_sub* sub, int fd, volatile sig_atomic_t* stop)
{
    uint8_t buf[9000];
    while (!*stop) {
        struct pollfd p;
        uint32_t wait = ln_pull_poll(sub, ln_pull_udp_now_ms());
        int n;
        p.fd = fd;
        p.events = POLLIN;
        p.revents = 0;
        n = poll(&p, 1, (int)(wait < 100 ? wait : 100));
        if (n < 0) {
            if (errno == EINTR)
                continue;
            return -1;
        }
        while (n > 0 && !*stop) {
            ssize_t got = recv(fd, buf, sizeof buf, MSG_DONTWAIT);
            if (got < 0) {
                if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR)
                    break;
                if (errno == ECONNREFUSED) /* nothing listens (yet): DIT keeps retrying */
                    continue;
                return -1;
            }
            ln_pull_receive(sub, buf, (size_t)got, ln_pull_udp_now_ms());
        }
    }
    return 0;
}
