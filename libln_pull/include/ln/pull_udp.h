/* ln/pull_udp.h — POSIX glue for the pull consumer (ln/pull.h): a connected UDP socket to the
 * producer, a send callback over it, a monotonic ms clock, and a blocking loop that feeds the
 * subscription until a stop flag is set.  Kept out of the portable core. */
#ifndef LN_PULL_UDP_H
#define LN_PULL_UDP_H

#include <signal.h>
#include <stdint.h>

#include "pull.h"

#ifdef __cplusplus
extern "C" {
#endif

/* A UDP socket connected to host:port (name or address, IPv4 or IPv6); the fd, or -1 with
 * errno set (EAI errors of getaddrinfo are reported as -1 with errno = EHOSTUNREACH). */
LN_NDN_EXPORT int ln_pull_udp_open(const char* host, uint16_t port);
/* An ln_pull_send_fn: `user` is a pointer to the int fd. */
LN_NDN_EXPORT void ln_pull_udp_send(void* user, const uint8_t* packet, size_t size);
/* CLOCK_MONOTONIC in ms, wrapping at 2^32. */
LN_NDN_EXPORT uint32_t ln_pull_udp_now_ms(void);
/* Receives on fd and drives `sub` (ln_pull_receive / ln_pull_poll) until *stop becomes non-zero
 * (checked at least every 100 ms); 0, or -1 with errno set if poll() or recv() failed. */
LN_NDN_EXPORT int ln_pull_udp_run(ln_pull_sub* sub, int fd, volatile sig_atomic_t* stop);

#ifdef __cplusplus
}
#endif
#endif
