/* pull_echo.c — prints the samples of a pull topic (docs/pull.md) as the tiny consumer of
 * libln_pull sees them: seq, age (now − publish time, ms) and, for robot/joint_state samples
 * such as the demo's arm.state, the first joint positions (else the first bytes in hex).
 * Usage: pull_echo [--naive | --deadline MS | --poll MS] [--window K] [--count N]
 *                  HOST PORT /PREFIX/TOPIC
 * The default is DIT with every hardening and a 100 ms deadline; Ctrl-C ends it and prints
 * the subscription's counters. */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "ln/pull_udp.h"
#include "robot_messages.h"

static volatile sig_atomic_t stop;
static unsigned long count, wanted;

static void on_signal(int sig)
{
    (void)sig;
    stop = 1;
}

static uint64_t realtime_us(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    return (uint64_t)ts.tv_sec * 1000000u + (uint64_t)ts.tv_nsec / 1000u;
}

static void on_data(void* user, uint64_t seq, const uint8_t* payload, size_t size,
                    uint64_t publish_us)
{
    (void)user;
    double age_ms = publish_us ? ((double)realtime_us() - (double)publish_us) / 1000.0 : 0.0;
    printf("seq %llu  age %7.2f ms  ", (unsigned long long)seq, age_ms);
    if (size == sizeof(robot_joint_state_t)) {
        robot_joint_state_t s;
        memcpy(&s, payload, sizeof s);
        printf("cycle %u  q = [%.3f %.3f %.3f ...]\n", s.cycle, s.position[0], s.position[1],
               s.position[2]);
    } else {
        printf("%zu bytes:", size);
        for (size_t i = 0; i < size && i < 16; i++)
            printf(" %02x", payload[i]);
        printf("%s\n", size > 16 ? " ..." : "");
    }
    fflush(stdout);
    if (wanted && ++count >= wanted)
        stop = 1;
}

static void on_event(void* user, int event, uint64_t seq, uint32_t t_ms)
{
    static const char* names[] = {"", "timeout", "nack", "sync"};
    (void)user;
    fprintf(stderr, "[%s seq %llu, t = %u ms]\n", names[event & 3], (unsigned long long)seq, t_ms);
}

static int usage(void)
{
    fprintf(stderr, "usage: pull_echo [--naive | --deadline MS | --poll MS] [--window K] "
                    "[--count N] HOST PORT /PREFIX/TOPIC\n");
    return 2;
}

int main(int argc, char** argv)
{
    ln_pull_options o;
    ln_pull_sub sub;
    int window = 0, i;
    ln_pull_options_hardened(&o, 100);
    for (i = 1; i < argc && argv[i][0] == '-' && argv[i][1] == '-'; i++) {
        const char* opt = argv[i];
        if (strcmp(opt, "--naive") == 0) {
            ln_pull_options_naive(&o);
            continue;
        }
        if (i + 1 >= argc)
            return usage();
        unsigned long v = strtoul(argv[++i], NULL, 10);
        if (strcmp(opt, "--deadline") == 0 && v > 0)
            ln_pull_options_hardened(&o, (uint32_t)v);
        else if (strcmp(opt, "--poll") == 0 && v > 0)
            o.poll_ms = (uint32_t)v;
        else if (strcmp(opt, "--window") == 0 && v >= 1 && v <= LN_PULL_MAX_WINDOW)
            window = (int)v;
        else if (strcmp(opt, "--count") == 0)
            wanted = v;
        else
            return usage();
    }
    if (window)
        o.window = (uint8_t)window;
    if (argc - i != 3)
        return usage();
    unsigned long port = strtoul(argv[i + 1], NULL, 10);
    if (port == 0 || port > 65535)
        return usage();
    int fd = ln_pull_udp_open(argv[i], (uint16_t)port);
    if (fd < 0) {
        fprintf(stderr, "pull_echo: %s:%lu: %s\n", argv[i], port, strerror(errno));
        return 1;
    }
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
    int rc = ln_pull_start(&sub, argv[i + 2], &o, ln_pull_udp_send, on_data, on_event, &fd,
                           ln_pull_udp_now_ms(), (uint32_t)realtime_us());
    if (rc < 0) {
        fprintf(stderr, "pull_echo: %s: %s\n", argv[i + 2], ln_ndn_strerror(rc));
        return 1;
    }
    if (ln_pull_udp_run(&sub, fd, &stop) < 0) {
        fprintf(stderr, "pull_echo: receive: %s\n", strerror(errno));
        return 1;
    }
    fprintf(stderr,
            "pull_echo: %u samples, %u interests (%u sync), %u timeouts, %u nacks, %u late, "
            "%u bad, t = %u ms\n",
            sub.stats.data, sub.stats.interests, sub.stats.syncs, sub.stats.timeouts,
            sub.stats.nacks, sub.stats.late, sub.stats.bad, sub.t_ms);
    return 0;
}
