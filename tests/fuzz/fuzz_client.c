/* fuzz_client.c — fuzz target: a real ln_client (client.c, client_conn.c) against a hostile
 * manager: a thread on 127.0.0.1 sends the input as everything the manager says and hangs up,
 * while the client does its handshake and TOPIC_INFO, CLOSE_PORT and FIND_SERVICE round trips. */
#define _GNU_SOURCE 1
#include <arpa/inet.h>
#include <errno.h>
#include <netinet/in.h>
#include <pthread.h>
#include <semaphore.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include "client_internal.h"
#include "fuzz.h"
#include "proto.h"

static int listen_fd = -1;
static char address[32];
static const uint8_t* input;
static size_t input_size;
static sem_t served; /* posted by the manager thread when a connection is over */

static void* manager(void* arg)
{
    (void)arg;
    for (;;) {
        int fd = accept(listen_fd, NULL, NULL);
        if (fd < 0)
            continue;
        /* The client sends before it reads, so this never deadlocks; once the client closes,
         * the rest of the input fails to send (EPIPE), as with a real manager.  EINTR (from
         * libFuzzer's SIGALRM, see below) is retried. */
        for (size_t off = 0; off < input_size;) {
            ssize_t n = send(fd, input + off, input_size - off, MSG_NOSIGNAL);
            if (n < 0 && errno == EINTR)
                continue;
            if (n <= 0)
                break;
            off += (size_t)n;
        }
        shutdown(fd, SHUT_WR);
        char sink[4096];
        ssize_t n;
        while ((n = recv(fd, sink, sizeof sink, 0)) > 0 || (n < 0 && errno == EINTR))
            ; /* whatever the client says, until it closes */
        close(fd);
        sem_post(&served);
    }
    return NULL;
}

static void start_manager(void)
{
    struct sockaddr_in a = {.sin_family = AF_INET, .sin_addr.s_addr = htonl(INADDR_LOOPBACK)};
    socklen_t len = sizeof a;
    pthread_t thread;
    listen_fd = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (listen_fd < 0 || bind(listen_fd, (struct sockaddr*)&a, sizeof a) != 0 ||
        listen(listen_fd, 4) != 0 || getsockname(listen_fd, (struct sockaddr*)&a, &len) != 0 ||
        sem_init(&served, 0, 0) != 0 || pthread_create(&thread, NULL, manager, NULL) != 0)
        abort();
    snprintf(address, sizeof address, "127.0.0.1:%u", (unsigned)ntohs(a.sin_port));
}

static void request(ln_client* c, uint16_t type, ln_wbuf* body)
{
    uint16_t reply_type;
    ln_rbuf reply;
    if (ln_client_request(c, type, body, &reply_type, &reply) == LN_OK) {
        /* the reply (after its request id) was checked against its type: it reads whole */
        char text[LN_PROTO_MAX_STR + 1];
        if (reply_type == LN_MSG_TOPIC_INFO_OK) {
            ln_rbuf_str(&reply, text, sizeof text);
            ln_rbuf_u64(&reply);
            ln_rbuf_u32(&reply);
            ln_rbuf_u32(&reply);
            ln_rbuf_u32(&reply);
        } else if (reply_type == LN_MSG_SERVICE_INFO) {
            for (int i = 0; i < 4; i++)
                ln_rbuf_str(&reply, text, sizeof text);
            ln_rbuf_u16(&reply);
            ln_rbuf_str(&reply, text, sizeof text);
        }
        if (ln_rbuf_end(&reply) != LN_OK)
            abort();
    }
    ln_wbuf_free(body);
}

int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    if (listen_fd < 0)
        start_manager();
    input = data;
    input_size = size;
    ln_client_options o;
    ln_client_options_init(&o);
    o.manager = address;
    o.timeout = 5;
    o.flags = LN_CLIENT_NO_RECONNECT;
    ln_client* c = NULL;
    if (ln_client_create(&c, "fuzz", &o) == LN_OK) {
        ln_wbuf b;
        ln_wbuf_init(&b);
        ln_wbuf_str(&b, "/arm/state");
        request(c, LN_MSG_TOPIC_INFO, &b);
        ln_wbuf_init(&b);
        ln_wbuf_u32(&b, 7);
        request(c, LN_MSG_CLOSE_PORT, &b);
        ln_wbuf_init(&b);
        ln_wbuf_str(&b, "planner");
        ln_wbuf_str(&b, "robot/plan_path");
        ln_wbuf_u64(&b, 42);
        request(c, LN_MSG_FIND_SERVICE, &b);
        ln_client_destroy(c);
    }
    /* The next input gets a fresh connection; a client that never connected is a bug here.
     * libFuzzer's -timeout watchdog is a SIGALRM every timeout/2 + 1 s without SA_RESTART,
     * which cuts sem_timedwait short with EINTR: wait on, for the same absolute deadline. */
    struct timespec limit;
    clock_gettime(CLOCK_REALTIME, &limit);
    limit.tv_sec += 10;
    int rc;
    while ((rc = sem_timedwait(&served, &limit)) != 0 && errno == EINTR)
        ;
    if (rc != 0) {
        fprintf(stderr, "fuzz_client: the client never talked to the manager (%s)\n",
                strerror(errno));
        abort();
    }
    return 0;
}

/* ---- seeds: a manager's answers, built with the frame encoder ---------------------------- */

static void welcome(ln_wbuf* b)
{
    size_t s = ln_proto_frame_begin(b, LN_MSG_WELCOME);
    ln_wbuf_u16(b, LN_PROTO_VERSION);
    ln_wbuf_u32(b, 42);
    ln_wbuf_str(b, "fuzz-2");
    ln_wbuf_str(b, "testinstance");
    ln_proto_frame_end(b, s);
}

void ln_fuzz_seeds(ln_fuzz_emit* emit)
{
    ln_wbuf b;
    ln_wbuf_init(&b);
    welcome(&b);
    size_t s = ln_proto_frame_begin(&b, LN_MSG_TOPIC_INFO_OK);
    ln_wbuf_u32(&b, 1);
    ln_wbuf_str(&b, "robot/joint_state");
    ln_wbuf_u64(&b, 0x1234);
    ln_wbuf_u32(&b, 176);
    ln_wbuf_u32(&b, 1);
    ln_wbuf_u32(&b, 0);
    ln_proto_frame_end(&b, s);
    s = ln_proto_frame_begin(&b, LN_MSG_OK);
    ln_wbuf_u32(&b, 2);
    ln_proto_frame_end(&b, s);
    s = ln_proto_frame_begin(&b, LN_MSG_SERVICE_INFO);
    ln_wbuf_u32(&b, 3);
    ln_wbuf_str(&b, "planner");
    ln_wbuf_str(&b, "host-1");
    ln_wbuf_str(&b, "/tmp/ln-0/testinstance/svc-planner");
    ln_wbuf_str(&b, "127.0.0.1");
    ln_wbuf_u16(&b, 40000);
    ln_wbuf_str(&b, "double 8 7|uint32_t 4 1");
    ln_proto_frame_end(&b, s);
    emit("session", b.data, b.len);
    ln_wbuf_free(&b);

    ln_wbuf_init(&b);
    welcome(&b);
    s = ln_proto_frame_begin(&b, LN_MSG_ERROR);
    ln_wbuf_u32(&b, 1);
    ln_wbuf_i32(&b, LN_ENOTFOUND);
    ln_wbuf_str(&b, "no topic /arm/state");
    ln_proto_frame_end(&b, s);
    emit("welcome_error", b.data, b.len);
    ln_wbuf_free(&b);

    ln_wbuf_init(&b);
    s = ln_proto_frame_begin(&b, LN_MSG_ERROR);
    ln_wbuf_u32(&b, 0);
    ln_wbuf_i32(&b, LN_EVERSION);
    ln_wbuf_str(&b, "manager speaks protocol 4");
    ln_proto_frame_end(&b, s);
    emit("refused", b.data, b.len);
    ln_wbuf_free(&b);
}
