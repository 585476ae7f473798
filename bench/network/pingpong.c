/* pingpong.c — the raw floor under topics between hosts: UDP and TCP ping-pong (the echo side
 * receives a whole message, then sends it back; the ping side times every round trip) and a
 * TCP stream of fixed-size messages for throughput, whose ends report their CPU time.  No
 * libln: plain sockets. */
#include <arpa/inet.h>
#include <errno.h>
#include <inttypes.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include "bench_common.h"
#include "bench_io.h"

#define UDP_MAX 65507             /* largest UDP payload over IPv4 */
#define RETRY_MS 1000             /* UDP: resend a ping not answered within this */
#define GIVE_UP_NS 30000000000ull /* UDP: fail after this long without any answer */

static const char usage[] =
    "usage: pingpong udp-echo PORT                                echo datagrams until an "
    "empty one\n"
    "       pingpong udp-ping HOST PORT SIZE COUNT WARMUP OUT     COUNT round trips (ns) to OUT\n"
    "       pingpong tcp-echo PORT SIZE                           echo SIZE-byte messages "
    "until EOF\n"
    "       pingpong tcp-ping HOST PORT SIZE COUNT WARMUP OUT     COUNT round trips (ns) to OUT\n"
    "       pingpong tcp-sink PORT SIZE                           count SIZE-byte messages "
    "until EOF\n"
    "       pingpong tcp-source HOST PORT SIZE COUNT              send COUNT messages at once\n"
    "Servers print \"ready\" once they listen; the other modes print one JSON line (sink and\n"
    "source with cpu_s, their CPU seconds, user + system).\n"
    "Every message starts with its number (uint64); round trips check it.\n";

static uint64_t number(const char* text, uint64_t max, const char* what)
{
    char* end;
    errno = 0;
    unsigned long long v = strtoull(text, &end, 10);
    if (errno || !*text || *end || v > max) {
        fprintf(stderr, "pingpong: %s must be a number up to %" PRIu64 ": %s\n", what, max, text);
        exit(2);
    }
    return v;
}

/* SIZE of a message: every message starts with its number (uint64). */
static size_t message_size(const char* text, uint64_t max)
{
    size_t size = number(text, max, "SIZE");
    if (size < 8) {
        fprintf(stderr, "pingpong: SIZE must be at least 8\n");
        exit(2);
    }
    return size;
}

/* What the pinging side takes (HOST PORT SIZE COUNT WARMUP OUT) and needs. */
typedef struct ping_args {
    size_t size;
    uint64_t count, warmup;
    uint8_t *out, *in; /* a message out, its echo in */
    uint64_t* rtt;     /* COUNT round trips, ns */
} ping_args;

static ping_args ping_setup(char** argv, uint64_t max_size)
{
    ping_args a = {.size = message_size(argv[4], max_size),
                   .count = number(argv[5], UINT32_MAX, "COUNT"),
                   .warmup = number(argv[6], UINT32_MAX, "WARMUP")};
    a.out = bench_alloc(a.size);
    a.in = bench_alloc(a.size);
    a.rtt = calloc(a.count ? a.count : 1, sizeof *a.rtt);
    if (!a.rtt)
        bench_die("calloc");
    return a;
}

/* A socket bound to every IPv4 address at `port` (listening, for TCP). */
static int server_socket(int type, const char* port_text)
{
    struct sockaddr_in sa = {.sin_family = AF_INET,
                             .sin_addr.s_addr = htonl(INADDR_ANY),
                             .sin_port = htons((uint16_t)number(port_text, 65535, "PORT"))};
    int fd = socket(AF_INET, type | SOCK_CLOEXEC, 0), one = 1;
    if (fd < 0)
        bench_die("socket");
    if (setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one) != 0)
        bench_die("SO_REUSEADDR");
    if (bind(fd, (struct sockaddr*)&sa, sizeof sa) != 0)
        bench_die("bind");
    if (type == SOCK_STREAM && listen(fd, 1) != 0)
        bench_die("listen");
    return fd;
}

/* A socket connected to host:port (for UDP: the only peer it talks to). */
static int client_socket(int type, const char* host, const char* port)
{
    struct addrinfo hints = {.ai_family = AF_INET, .ai_socktype = type}, *res;
    int rc = getaddrinfo(host, port, &hints, &res);
    if (rc != 0) {
        fprintf(stderr, "pingpong: %s:%s: %s\n", host, port, gai_strerror(rc));
        exit(2);
    }
    int fd = socket(res->ai_family, res->ai_socktype | SOCK_CLOEXEC, res->ai_protocol);
    if (fd < 0)
        bench_die("socket");
    if (connect(fd, res->ai_addr, res->ai_addrlen) != 0)
        bench_die("connect");
    freeaddrinfo(res);
    return fd;
}

static void no_delay(int fd)
{
    int one = 1;
    if (setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one) != 0)
        bench_die("TCP_NODELAY");
}

static int accept_one(int lfd)
{
    int fd = accept4(lfd, NULL, NULL, SOCK_CLOEXEC);
    if (fd < 0)
        bench_die("accept");
    close(lfd);
    no_delay(fd);
    return fd;
}

static int udp_echo(const char* port)
{
    int fd = server_socket(SOCK_DGRAM, port);
    uint8_t* buf = bench_alloc(UDP_MAX);
    bench_ready();
    for (;;) {
        struct sockaddr_storage from;
        socklen_t len = sizeof from;
        ssize_t n = recvfrom(fd, buf, UDP_MAX, 0, (struct sockaddr*)&from, &len);
        if (n < 0 && errno == EINTR)
            continue;
        if (n < 0)
            bench_die("recvfrom");
        if (n == 0)
            break;
        if (sendto(fd, buf, (size_t)n, 0, (struct sockaddr*)&from, len) < 0)
            bench_die("sendto");
    }
    close(fd);
    return 0;
}

/* One round trip of message `i`: send, wait for the datagram with that number (older
 * numbers are late answers to resent pings and are skipped), resend after RETRY_MS.  The
 * time from the first send, or 0 if the ping had to be resent (not a clean sample). */
static uint64_t udp_round_trip(int fd, uint8_t* out, uint8_t* in, size_t size, uint64_t i,
                               uint64_t* resent)
{
    memcpy(out, &i, sizeof i);
    uint64_t t0 = bench_now_ns(), last_answer = t0;
    int retried = 0;
    if (send(fd, out, size, 0) < 0 && errno != ECONNREFUSED)
        bench_die("send");
    for (;;) {
        struct pollfd p = {.fd = fd, .events = POLLIN};
        int rc = poll(&p, 1, RETRY_MS);
        if (rc < 0 && errno == EINTR)
            continue;
        if (rc < 0)
            bench_die("poll");
        if (rc == 0) {
            if (bench_now_ns() - last_answer > GIVE_UP_NS) {
                fprintf(stderr, "pingpong: no answer for %llu s\n", GIVE_UP_NS / 1000000000ull);
                exit(1);
            }
            (*resent)++;
            retried = 1;
            if (send(fd, out, size, 0) < 0 && errno != ECONNREFUSED)
                bench_die("send");
            continue;
        }
        ssize_t n = recv(fd, in, size, 0);
        if (n < 0 && errno == ECONNREFUSED) /* the echo side is not there (yet) */
            continue;
        if (n < 0)
            bench_die("recv");
        uint64_t got, t1 = bench_now_ns();
        last_answer = t1;
        memcpy(&got, in, sizeof got);
        if ((size_t)n == size && got == i)
            return retried ? 0 : t1 - t0;
    }
}

static int udp_ping(char** argv)
{
    ping_args a = ping_setup(argv, UDP_MAX);
    size_t size = a.size;
    uint64_t count = a.count, warmup = a.warmup, *rtt = a.rtt;
    uint8_t *out = a.out, *in = a.in;
    int fd = client_socket(SOCK_DGRAM, argv[2], argv[3]);
    uint64_t resent = 0, kept = 0;
    for (uint64_t i = 0; i < warmup + count; i++) {
        uint64_t t = udp_round_trip(fd, out, in, size, i, &resent);
        if (i >= warmup && t != 0)
            rtt[kept++] = t;
    }
    for (int k = 0; k < 3; k++) /* tell the echo side to end; it may miss it, then it is killed */
        send(fd, out, 0, 0);
    bench_write_samples(argv[7], rtt, kept);
    printf("{\"round_trips\": %" PRIu64 ", \"resent\": %" PRIu64 ", \"excluded\": %" PRIu64 "}\n",
           kept, resent, count - kept);
    return 0;
}

static int tcp_echo(const char* port, size_t size)
{
    int lfd = server_socket(SOCK_STREAM, port);
    bench_ready();
    int fd = accept_one(lfd);
    uint8_t* buf = bench_alloc(size);
    while (bench_read_full(fd, buf, size))
        bench_write_full(fd, buf, size);
    close(fd);
    return 0;
}

static int tcp_ping(char** argv)
{
    ping_args a = ping_setup(argv, SIZE_MAX);
    size_t size = a.size;
    uint64_t count = a.count, warmup = a.warmup, *rtt = a.rtt;
    uint8_t *out = a.out, *in = a.in;
    int fd = client_socket(SOCK_STREAM, argv[2], argv[3]);
    no_delay(fd);
    for (uint64_t i = 0; i < warmup + count; i++) {
        uint64_t t0 = bench_now_ns(), got;
        memcpy(out, &i, sizeof i);
        bench_write_full(fd, out, size);
        if (!bench_read_full(fd, in, size)) {
            fprintf(stderr, "pingpong: the echo side closed the connection\n");
            return 1;
        }
        uint64_t t1 = bench_now_ns();
        memcpy(&got, in, sizeof got);
        if (got != i) {
            fprintf(stderr, "pingpong: round trip %" PRIu64 " came back as %" PRIu64 "\n", i, got);
            return 1;
        }
        if (i >= warmup)
            rtt[i - warmup] = t1 - t0;
    }
    close(fd);
    bench_write_samples(argv[7], rtt, count);
    printf("{\"round_trips\": %" PRIu64 ", \"resent\": 0, \"excluded\": 0}\n", count);
    return 0;
}

/* Received rate is taken from the end of the first message to the end of the last one. */
static int tcp_sink(const char* port, size_t size)
{
    int lfd = server_socket(SOCK_STREAM, port);
    bench_ready();
    int fd = accept_one(lfd);
    uint8_t* buf = bench_alloc(size);
    uint64_t received = 0, disorder = 0, last = 0, first_ns = 0, last_ns = 0;
    while (bench_read_full(fd, buf, size)) {
        uint64_t counter;
        last_ns = bench_now_ns();
        memcpy(&counter, buf, sizeof counter);
        if (received++ == 0)
            first_ns = last_ns;
        else if (counter != last + 1)
            disorder++;
        last = counter;
    }
    close(fd);
    printf("{\"received\": %" PRIu64 ", \"bytes\": %" PRIu64 ", \"overruns\": 0, "
           "\"disorder\": %" PRIu64 ", \"elapsed_s\": %.9f, \"cpu_s\": %.6f}\n",
           received, received * (uint64_t)size, disorder, (double)(last_ns - first_ns) * 1e-9,
           bench_cpu_s());
    return 0;
}

static int tcp_source(char** argv)
{
    size_t size = message_size(argv[4], SIZE_MAX);
    uint64_t count = number(argv[5], UINT64_MAX, "COUNT");
    int fd = client_socket(SOCK_STREAM, argv[2], argv[3]);
    uint8_t* buf = bench_alloc(size);
    uint64_t t0 = bench_now_ns();
    for (uint64_t i = 0; i < count; i++) {
        memcpy(buf, &i, sizeof i);
        bench_write_full(fd, buf, size);
    }
    uint64_t t1 = bench_now_ns();
    if (shutdown(fd, SHUT_WR) != 0) /* then wait until the sink has read everything */
        bench_die("shutdown");
    while (read(fd, buf, size) > 0) {
    }
    close(fd);
    printf("{\"sent\": %" PRIu64 ", \"elapsed_s\": %.9f, \"cpu_s\": %.6f}\n", count,
           (double)(t1 - t0) * 1e-9, bench_cpu_s());
    return 0;
}

int main(int argc, char** argv)
{
    const char* mode = argc > 1 ? argv[1] : "";
    if (argc == 3 && strcmp(mode, "udp-echo") == 0)
        return udp_echo(argv[2]);
    if (argc == 8 && strcmp(mode, "udp-ping") == 0)
        return udp_ping(argv);
    if (argc == 4 && strcmp(mode, "tcp-echo") == 0)
        return tcp_echo(argv[2], number(argv[3], SIZE_MAX, "SIZE"));
    if (argc == 8 && strcmp(mode, "tcp-ping") == 0)
        return tcp_ping(argv);
    if (argc == 4 && strcmp(mode, "tcp-sink") == 0)
        return tcp_sink(argv[2], message_size(argv[3], SIZE_MAX));
    if (argc == 6 && strcmp(mode, "tcp-source") == 0)
        return tcp_source(argv);
    fputs(usage, stderr);
    return 2;
}
