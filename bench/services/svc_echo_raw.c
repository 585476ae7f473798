/* svc_echo_raw.c — the floor under svc_ln: a blocking SOCK_STREAM Unix socket between two
 * processes; the server reads 64 bytes and writes them back, the client times every call. */
#include <errno.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include "bench_common.h"
#include "bench_io.h"

#define MSG 64

static const char usage[] =
    "usage: svc_echo_raw server PATH                     echo 64-byte messages until EOF\n"
    "       svc_echo_raw client PATH COUNT WARMUP OUT    COUNT round trips (ns) to OUT\n";

static struct sockaddr_un address(const char* path)
{
    struct sockaddr_un sa = {.sun_family = AF_UNIX};
    if (strlen(path) >= sizeof sa.sun_path) {
        fprintf(stderr, "svc_echo_raw: path too long: %s\n", path);
        exit(2);
    }
    strcpy(sa.sun_path, path);
    return sa;
}

static int server(const char* path)
{
    struct sockaddr_un sa = address(path);
    int lfd = socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (lfd < 0)
        bench_die("socket");
    if (bind(lfd, (struct sockaddr*)&sa, sizeof sa) != 0)
        bench_die("bind");
    if (listen(lfd, 1) != 0)
        bench_die("listen");
    bench_ready();
    int fd = accept(lfd, NULL, NULL);
    if (fd < 0)
        bench_die("accept");
    uint8_t buf[MSG];
    while (bench_read_full(fd, buf, MSG))
        bench_write_full(fd, buf, MSG);
    close(fd);
    close(lfd);
    unlink(path);
    return 0;
}

static int client(const char* path, uint64_t count, uint64_t warmup, const char* out)
{
    struct sockaddr_un sa = address(path);
    int fd = socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (fd < 0)
        bench_die("socket");
    if (connect(fd, (struct sockaddr*)&sa, sizeof sa) != 0)
        bench_die("connect");
    uint64_t* rtt = calloc(count ? count : 1, sizeof(*rtt));
    if (!rtt)
        bench_die("calloc");
    uint8_t req[MSG], resp[MSG];
    memset(req, 0x5a, sizeof req);
    for (uint64_t i = 0; i < warmup + count; i++) {
        uint64_t t0 = bench_now_ns(), got;
        memcpy(req, &i, sizeof i);
        bench_write_full(fd, req, MSG);
        if (!bench_read_full(fd, resp, MSG)) {
            fprintf(stderr, "svc_echo_raw: server closed the connection\n");
            return 1;
        }
        uint64_t t1 = bench_now_ns();
        memcpy(&got, resp, sizeof got);
        if (got != i) {
            fprintf(stderr, "svc_echo_raw: call %llu came back as %llu\n", (unsigned long long)i,
                    (unsigned long long)got);
            return 1;
        }
        if (i >= warmup)
            rtt[i - warmup] = t1 - t0;
    }
    close(fd);
    bench_write_samples(out, rtt, count);
    free(rtt);
    return 0;
}

int main(int argc, char** argv)
{
    if (argc == 3 && strcmp(argv[1], "server") == 0)
        return server(argv[2]);
    if (argc == 6 && strcmp(argv[1], "client") == 0)
        return client(argv[2], strtoull(argv[3], NULL, 10), strtoull(argv[4], NULL, 10), argv[5]);
    fputs(usage, stderr);
    return 2;
}
