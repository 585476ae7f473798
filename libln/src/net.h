/* net.h — the TCP plumbing of the manager connection: connect with a deadline, whole-buffer
 * reads and writes with a deadline.  Thin over the syscalls: results are errno values, and
 * the caller, who knows the context, turns them into LN_E* codes and error texts. */
#ifndef LN_NET_H
#define LN_NET_H

#include <netdb.h>
#include <stddef.h>
#include <time.h>

/* Every wait below also ends, with ECANCELED, once `cancel_fd` is readable (-1: no such fd):
 * ln_client_destroy uses it to stop a reconnect in progress. */

/* Result of ln_net_read_all when the peer closed the connection before all bytes came. */
#define LN_NET_EOF (-1)

/* Fills *ts with the CLOCK_MONOTONIC time `timeout` seconds from now and returns ts, or
 * returns NULL (no deadline: wait forever) for a negative timeout. */
const struct timespec* ln_net_deadline(struct timespec* ts, double timeout);

/* Resolves host and a numeric port for TCP; returns 0 with *out (free with freeaddrinfo) or
 * a getaddrinfo error code (EAI_*; for EAI_SYSTEM errno says more). */
int ln_net_resolve(const char* host, const char* port, struct addrinfo** out);

/* Connects to the first address of `ai` that accepts before the deadline; the socket is
 * non-blocking, close-on-exec and has TCP_NODELAY.  Returns 0 with *fd, or the errno of the
 * last attempt (ETIMEDOUT when the deadline passed). */
int ln_net_connect(const struct addrinfo* ai, const struct timespec* deadline, int cancel_fd,
                   int* fd);

/* Sends all len bytes (never raises SIGPIPE).  Returns 0 or an errno value (ETIMEDOUT when
 * the deadline passed with bytes still unsent). */
int ln_net_write_all(int fd, const void* buf, size_t len, const struct timespec* deadline,
                     int cancel_fd);

/* Receives exactly len bytes.  Returns 0, LN_NET_EOF if the peer closed the connection
 * first, or an errno value (ETIMEDOUT when the deadline passed). */
int ln_net_read_all(int fd, void* buf, size_t len, const struct timespec* deadline, int cancel_fd);

/* Waits until fd has data or the peer closed it.  Returns 0 or an errno value (ETIMEDOUT). */
int ln_net_wait_readable(int fd, const struct timespec* deadline, int cancel_fd);

#endif /* LN_NET_H */
