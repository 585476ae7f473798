/* test_svc_tap.c — the provider's side of recording calls (libln/src/svc_tap.c) on a socket pair
 * standing in for the recorder: the CALL frame's bytes, a recorder that does not read (the
 * provider's calls go on, the queue drops and counts), a recorder that hangs up or dies (the
 * tap is forgotten) and stopping while a write is stuck. */
#define _GNU_SOURCE 1
#include <fcntl.h>
#include <poll.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include "ln_test.h"
#include "svc_internal.h"

#define WAIT_MS 10000 /* only an upper bound against a hang */

static ln_svc_endpoint ep = {.caller = "the_caller"};

static ln_service_provider* provider(void)
{
    ln_service_provider* p = calloc(1, sizeof *p);
    p->taps = ln_svc_taps_new();
    return p;
}

static ln_service_request request(ln_service_provider* p, const void* wire, size_t len)
{
    ln_service_request r = {.prov = p,
                            .ep = &ep,
                            .wire = wire,
                            .wire_len = len,
                            .t_real_ns = 1234567890123LL,
                            .t_mono_ns = 1};
    return r;
}

/* Reads one whole frame from fd into buf (blocking up to WAIT_MS): its body length, or -1. */
static long read_frame(int fd, uint8_t* buf, size_t cap, uint16_t* type)
{
    size_t got = 0, want = 6;
    while (got < want) {
        struct pollfd pfd = {.fd = fd, .events = POLLIN};
        if (poll(&pfd, 1, WAIT_MS) != 1)
            return -1;
        ssize_t n = read(fd, buf + got, want - got);
        if (n <= 0)
            return -1;
        got += (size_t)n;
        if (got == 6) {
            uint32_t length = (uint32_t)buf[0] | (uint32_t)buf[1] << 8 | (uint32_t)buf[2] << 16 |
                              (uint32_t)buf[3] << 24;
            want = 4 + length;
            if (want > cap)
                return -1;
            *type = (uint16_t)(buf[4] | buf[5] << 8);
        }
    }
    return (long)want - 6;
}

static int wait_untapped(ln_service_provider* p)
{
    for (int i = 0; i < WAIT_MS && atomic_load(&p->tapped) != 0; i++)
        usleep(1000);
    return atomic_load(&p->tapped);
}

static void test_call_frame(void)
{
    ln_service_provider* p = provider();
    int sv[2];
    LN_CHECK_EQ(socketpair(AF_UNIX, SOCK_STREAM, 0, sv), 0);
    LN_CHECK(ln_svc_tap_add(p, sv[0]) > 0);
    LN_CHECK_EQ(atomic_load(&p->tapped), 1);
    const uint8_t req[] = {1, 2, 3}, resp[] = {9, 8};
    ln_service_request r = request(p, req, sizeof req);
    ln_svc_tap_call(p, &r, 0, resp, sizeof resp);
    ln_svc_tap_call(p, &r, LN_ESERVICE, "no", 2);
    uint8_t buf[256];
    uint16_t type;
    long n = read_frame(sv[1], buf, sizeof buf, &type);
    LN_CHECK_EQ(type, LN_SVC_CALL);
    /* u64 time, u64 duration, u64 dropped, i32 code, str caller, u32 3 + req, u32 2 + resp */
    LN_CHECK_EQ(n, 8 + 8 + 8 + 4 + 2 + 10 + 4 + 3 + 4 + 2);
    ln_rbuf rb;
    ln_rbuf_init(&rb, buf + 6, (size_t)n);
    LN_CHECK_EQ(ln_rbuf_u64(&rb), 1234567890123ULL);
    ln_rbuf_u64(&rb); /* duration: whatever the clock says */
    LN_CHECK_EQ(ln_rbuf_u64(&rb), 0);
    LN_CHECK_EQ(ln_rbuf_i32(&rb), 0);
    char caller[32];
    ln_rbuf_str(&rb, caller, sizeof caller);
    LN_CHECK_STREQ(caller, "the_caller");
    LN_CHECK_EQ(ln_rbuf_u32(&rb), 3);
    LN_CHECK(memcmp(rb.p, req, 3) == 0);
    rb.p += 3;
    rb.left -= 3;
    LN_CHECK_EQ(ln_rbuf_u32(&rb), 2);
    LN_CHECK(memcmp(rb.p, resp, 2) == 0);
    n = read_frame(sv[1], buf, sizeof buf, &type);
    LN_CHECK_EQ(n, 8 + 8 + 8 + 4 + 2 + 10 + 4 + 3 + 4 + 2);
    ln_rbuf_init(&rb, buf + 6 + 24, (size_t)n - 24);
    LN_CHECK_EQ(ln_rbuf_i32(&rb), LN_ESERVICE);
    /* a call that began before the tap is not recorded */
    r.t_mono_ns = 0;
    ln_svc_tap_call(p, &r, 0, resp, sizeof resp);
    struct pollfd pfd = {.fd = sv[1], .events = POLLIN};
    LN_CHECK_EQ(poll(&pfd, 1, 100), 0);
    close(sv[1]);
    ln_svc_taps_free(p);
    free(p);
}

static void test_slow_recorder_drops(void)
{
    ln_service_provider* p = provider();
    int sv[2];
    LN_CHECK_EQ(socketpair(AF_UNIX, SOCK_STREAM, 0, sv), 0);
    LN_CHECK(ln_svc_tap_add(p, sv[0]) > 0);
    enum { SIZE = 64 << 10, TOTAL = 400 };
    uint8_t* big = calloc(1, SIZE);
    ln_service_request r = request(p, big, SIZE);
    /* nobody reads: every call returns (a blocking provider would hang here) */
    for (int i = 0; i < TOTAL - 1; i++) {
        memcpy(big, &i, sizeof i);
        ln_svc_tap_call(p, &r, 0, "", 0);
    }
    static uint8_t buf[SIZE + 256];
    uint16_t type;
    int received = 0, last = -1, ordered = 1, marker = TOTAL - 1, sent = 0;
    uint64_t dropped = 0;
    /* take what was queued; once nothing comes, one more call that carries the drop count */
    for (int idle = 0; idle < WAIT_MS / 100;) {
        struct pollfd pfd = {.fd = sv[1], .events = POLLIN};
        if (poll(&pfd, 1, 100) != 1) {
            idle++;
            if (!sent) {
                memcpy(big, &marker, sizeof marker);
                ln_svc_tap_call(p, &r, 0, "", 0);
                sent = 1;
            }
            continue;
        }
        if (read_frame(sv[1], buf, sizeof buf, &type) < 0)
            break;
        int seq;
        memcpy(&seq, buf + 6 + 28 + 2 + 10 + 4, sizeof seq);
        ordered &= seq > last;
        last = seq;
        received++;
        if (seq == marker) {
            memcpy(&dropped, buf + 6 + 16, sizeof dropped);
            break;
        }
    }
    LN_CHECK_EQ(last, marker);
    LN_CHECK(ordered);
    LN_CHECK(dropped > 0);
    LN_CHECK_EQ((uint64_t)received + dropped, (uint64_t)TOTAL);
    free(big);
    close(sv[1]);
    ln_svc_taps_free(p);
    free(p);
}

static void test_recorder_gone(void)
{
    ln_service_provider* p = provider();
    int sv[2];
    LN_CHECK_EQ(socketpair(AF_UNIX, SOCK_STREAM, 0, sv), 0);
    LN_CHECK(ln_svc_tap_add(p, sv[0]) > 0);
    close(sv[1]); /* killed: the next write fails and the tap is forgotten */
    ln_service_request r = request(p, "x", 1);
    ln_svc_tap_call(p, &r, 0, "", 0);
    LN_CHECK_EQ(wait_untapped(p), 0);
    /* a hang-up seen by the group forgets it at once */
    LN_CHECK_EQ(socketpair(AF_UNIX, SOCK_STREAM, 0, sv), 0);
    int64_t id = ln_svc_tap_add(p, sv[0]);
    LN_CHECK_EQ(atomic_load(&p->tapped), 1);
    ln_svc_tap_hangup(p, id);
    LN_CHECK_EQ(atomic_load(&p->tapped), 0);
    close(sv[1]);
    ln_svc_taps_free(p);
    free(p);
}

static void test_free_while_a_write_is_stuck(void)
{
    ln_service_provider* p = provider();
    int sv[2];
    LN_CHECK_EQ(socketpair(AF_UNIX, SOCK_STREAM, 0, sv), 0);
    LN_CHECK(ln_svc_tap_add(p, sv[0]) > 0);
    uint8_t* big = calloc(1, 1 << 20);
    ln_service_request r = request(p, big, 1 << 20);
    for (int i = 0; i < 8; i++)
        ln_svc_tap_call(p, &r, 0, "", 0);
    usleep(20000);       /* let the sender block in its write */
    ln_svc_taps_free(p); /* must return: shutdown() ends the write */
    LN_CHECK(p->taps == NULL);
    free(big);
    close(sv[1]);
    free(p);
}

int main(void)
{
    LN_TEST_RUN(test_call_frame);
    LN_TEST_RUN(test_slow_recorder_drops);
    LN_TEST_RUN(test_recorder_gone);
    LN_TEST_RUN(test_free_while_a_write_is_stuck);
    LN_TEST_EXIT();
}
