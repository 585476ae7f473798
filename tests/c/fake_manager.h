/* fake_manager.h — a scripted stand-in for ln_manager for the client tests: one thread that
 * accepts one TCP connection (or `sessions` of them, one after the other: a restarted
 * manager) on 127.0.0.1 (ephemeral port) and runs a script against each, so each test
 * decides byte by byte what the client sees.  Also compiles the client code in, as
 * its internals (ln_client_request, the handle's fields) are hidden in libln.so. */
#ifndef LN_FAKE_MANAGER_H
#define LN_FAKE_MANAGER_H

#include <arpa/inet.h>
#include <errno.h>
#include <netinet/in.h>
#include <poll.h>
#include <pthread.h>
#include <semaphore.h>
#include <stdlib.h>
#include <sys/socket.h>
#include <unistd.h>

#include "../../libln/src/lasterror.c"
#include "../../libln/src/proto.c"
#include "client_wire.c" /* generated into the build tree from client.schema */
#include "../../libln/src/net.c"
#include "../../libln/src/client.c"
#include "../../libln/src/client_conn.c"
#include "../../libln/src/client_auth.c" /* admission by key: hidden in libln.so */
#include "../../libln/src/log_format.c"
#include "../../libln/src/client_log.c"
#include "../../libln/src/host_id.c" /* ln_host_id: not exported by libln.so */

/* client.c stops and frees service groups on destroy; these tests link no service code and
 * create no groups. */
void ln_svc_client_stop_pools(ln_client* c) { (void)c; }
void ln_svc_client_free(ln_client* c) { (void)c; }

#include "ln_test.h"

/* Each test program uses only some of the functions below. */
#define FAKE_FN static __attribute__((unused))

#define FAKE_WAIT_MS 10000 /* a fake that waits longer than this has lost its client */

struct fake {
    int listen_fd, port;
    char address[32]; /* "127.0.0.1:PORT" */
    pthread_t thread;
    void (*script)(struct fake* f, int fd);
    int variant;   /* for scripts that come in several flavours */
    int sessions;  /* connections to accept (fake_start: 1) */
    int session;   /* the one the script runs for, from 0 */
    sem_t go;      /* posted by the test to let a stalled script continue */
    sem_t reached; /* posted by a script to tell the test where it is */
    int errors;    /* checks that failed inside the fake (read after fake_stop) */
    int connected, saw_eof;
    uint32_t hello_magic, hello_pid, hello_flags;
    uint16_t hello_version;
    char hello_name[LN_PROTO_MAX_STR + 1], hello_lib[LN_PROTO_MAX_STR + 1];
    char hello_host[LN_PROTO_MAX_STR + 1];
    uint32_t closed_port; /* port id of the last CLOSE_PORT */
    uint8_t rx[65536];
};

#define FAKE_CHECK(f, cond)                                                                        \
    do {                                                                                           \
        if (!(cond)) {                                                                             \
            fprintf(stderr, "%s:%d: fake manager: check failed: %s\n", __FILE__, __LINE__, #cond); \
            (f)->errors++;                                                                         \
        }                                                                                          \
    } while (0)

/* 0 once all len bytes arrived, -1 at EOF (the client closed), -2 on an error or when
 * nothing came for FAKE_WAIT_MS (the client hangs or leaked the connection). */
FAKE_FN int fake_read_exact(int fd, void* buf, size_t len)
{
    uint8_t* p = buf;
    while (len > 0) {
        struct pollfd pfd = {.fd = fd, .events = POLLIN, .revents = 0};
        if (poll(&pfd, 1, FAKE_WAIT_MS) <= 0)
            return -2;
        ssize_t n = recv(fd, p, len, 0);
        if (n == 0 || (n < 0 && errno == ECONNRESET)) /* closed (with unread data: a reset) */
            return -1;
        if (n < 0)
            return -2;
        p += n;
        len -= (size_t)n;
    }
    return 0;
}

/* Receives one frame: 1 with its type and body, 0 when the client closed the connection. */
FAKE_FN int fake_recv(struct fake* f, int fd, uint16_t* type, ln_rbuf* body)
{
    uint8_t header[LN_PROTO_HEADER_SIZE];
    uint32_t len = 0;
    int rc = fake_read_exact(fd, header, sizeof header);
    if (rc != 0) {
        f->saw_eof = rc == -1; /* only a real end of stream counts as the client closing */
        return 0;
    }
    FAKE_CHECK(f, ln_proto_parse_header(header, &len, type) == LN_OK);
    FAKE_CHECK(f, len <= sizeof f->rx);
    if (len > sizeof f->rx || fake_read_exact(fd, f->rx, len) != 0)
        return 0;
    ln_rbuf_init(body, f->rx, len);
    return 1;
}

FAKE_FN void fake_send_raw(int fd, const void* data, size_t len)
{
    const uint8_t* p = data;
    while (len > 0) {
        ssize_t n = send(fd, p, len, MSG_NOSIGNAL);
        if (n <= 0)
            return; /* the client is gone; the test's own checks will tell */
        p += n;
        len -= (size_t)n;
    }
}

/* Frames of the manager side; `b` holds the frame being built (start at 0). */
FAKE_FN void fake_send(struct fake* f, int fd, ln_wbuf* b)
{
    FAKE_CHECK(f, ln_proto_frame_end(b, 0) == LN_OK);
    fake_send_raw(fd, b->data, b->len);
    ln_wbuf_free(b);
}

FAKE_FN void fake_welcome(struct fake* f, int fd, uint16_t version, const char* name)
{
    ln_wbuf b;
    ln_wbuf_init(&b);
    ln_proto_frame_begin(&b, LN_MSG_WELCOME);
    ln_wbuf_u16(&b, version);
    ln_wbuf_u32(&b, 42);
    ln_wbuf_str(&b, name);
    ln_wbuf_str(&b, "testinstance");
    fake_send(f, fd, &b);
}

FAKE_FN void fake_error(struct fake* f, int fd, uint32_t id, int32_t code, const char* text)
{
    ln_wbuf b;
    ln_wbuf_init(&b);
    ln_proto_frame_begin(&b, LN_MSG_ERROR);
    ln_wbuf_u32(&b, id);
    ln_wbuf_i32(&b, code);
    ln_wbuf_str(&b, text);
    fake_send(f, fd, &b);
}

/* TOPIC_INFO_OK that echoes the topic as md_name, so the test sees which request it answers. */
FAKE_FN void fake_topic_info_ok(struct fake* f, int fd, uint32_t id, const char* topic)
{
    ln_wbuf b;
    ln_wbuf_init(&b);
    ln_proto_frame_begin(&b, LN_MSG_TOPIC_INFO_OK);
    ln_wbuf_u32(&b, id);
    ln_wbuf_str(&b, topic);
    ln_wbuf_u64(&b, 0xfeedull);
    ln_wbuf_u32(&b, 64);
    ln_wbuf_u32(&b, 1);
    ln_wbuf_u32(&b, 2);
    fake_send(f, fd, &b);
}

/* Reads HELLO into f->hello_*; 1 if it was one. */
FAKE_FN int fake_hello(struct fake* f, int fd)
{
    uint16_t type = 0;
    ln_rbuf r;
    if (!fake_recv(f, fd, &type, &r))
        return 0;
    FAKE_CHECK(f, type == LN_MSG_HELLO);
    f->hello_magic = ln_rbuf_u32(&r);
    f->hello_version = ln_rbuf_u16(&r);
    f->hello_pid = ln_rbuf_u32(&r);
    ln_rbuf_str(&r, f->hello_name, sizeof f->hello_name);
    ln_rbuf_str(&r, f->hello_lib, sizeof f->hello_lib);
    ln_rbuf_str(&r, f->hello_host, sizeof f->hello_host);
    f->hello_flags = ln_rbuf_u32(&r);
    FAKE_CHECK(f, ln_rbuf_end(&r) == LN_OK);
    return type == LN_MSG_HELLO;
}

/* Receives one TOPIC_INFO: its request id and topic; 0 at EOF. */
FAKE_FN uint32_t fake_topic_info(struct fake* f, int fd, char* topic, size_t size)
{
    uint16_t type = 0;
    ln_rbuf r;
    if (!fake_recv(f, fd, &type, &r))
        return 0;
    FAKE_CHECK(f, type == LN_MSG_TOPIC_INFO);
    uint32_t id = ln_rbuf_u32(&r);
    ln_rbuf_str(&r, topic, size);
    FAKE_CHECK(f, ln_rbuf_end(&r) == LN_OK && id != 0);
    return id;
}

/* A well-behaved manager after the handshake: answers TOPIC_INFO (ERROR ENOTFOUND for topic
 * "missing") and CLOSE_PORT until the client disconnects. */
FAKE_FN void fake_serve(struct fake* f, int fd)
{
    uint16_t type;
    ln_rbuf r;
    while (fake_recv(f, fd, &type, &r)) {
        uint32_t id = ln_rbuf_u32(&r);
        if (type == LN_MSG_CLOSE_PORT) {
            f->closed_port = ln_rbuf_u32(&r);
            FAKE_CHECK(f, ln_rbuf_end(&r) == LN_OK);
            ln_wbuf b;
            ln_wbuf_init(&b);
            ln_proto_frame_begin(&b, LN_MSG_OK);
            ln_wbuf_u32(&b, id);
            fake_send(f, fd, &b);
            continue;
        }
        char topic[LN_PROTO_MAX_STR + 1];
        ln_rbuf_str(&r, topic, sizeof topic);
        FAKE_CHECK(f, type == LN_MSG_TOPIC_INFO && ln_rbuf_end(&r) == LN_OK);
        if (strcmp(topic, "missing") == 0)
            fake_error(f, fd, id, LN_ENOTFOUND, "topic 'missing' does not exist");
        else
            fake_topic_info_ok(f, fd, id, topic);
    }
}

/* The usual script: welcome under the requested name with "-2" appended, then serve. */
FAKE_FN void script_welcome(struct fake* f, int fd)
{
    if (!fake_hello(f, fd))
        return;
    char name[LN_PROTO_MAX_STR + 8];
    snprintf(name, sizeof name, "%s-2", f->hello_name);
    fake_welcome(f, fd, LN_PROTO_VERSION, name);
    fake_serve(f, fd);
}

FAKE_FN void* fake_main(void* arg)
{
    struct fake* f = arg;
    for (f->session = 0; f->session < f->sessions; f->session++) {
        struct pollfd pfd = {.fd = f->listen_fd, .events = POLLIN, .revents = 0};
        int fd = poll(&pfd, 1, FAKE_WAIT_MS) == 1 ? accept(f->listen_fd, NULL, NULL) : -1;
        FAKE_CHECK(f, fd >= 0);
        if (fd < 0)
            break;
        f->connected = 1;
        f->script(f, fd);
        close(fd);
    }
    return NULL;
}

/* Starts the fake's thread; `sessions` > 1 accepts that many connections in turn. */
FAKE_FN void fake_start_sessions(struct fake* f, void (*script)(struct fake*, int), int variant,
                                 int sessions);

FAKE_FN void fake_start(struct fake* f, void (*script)(struct fake*, int), int variant)
{
    fake_start_sessions(f, script, variant, 1);
}

FAKE_FN void fake_start_sessions(struct fake* f, void (*script)(struct fake*, int), int variant,
                                 int sessions)
{
    memset(f, 0, sizeof *f);
    f->script = script;
    f->variant = variant;
    f->sessions = 1;
    sem_init(&f->go, 0, 0);
    sem_init(&f->reached, 0, 0);
    struct sockaddr_in sa = {.sin_family = AF_INET, .sin_port = 0};
    sa.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t len = sizeof sa;
    f->listen_fd = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (f->listen_fd < 0 || bind(f->listen_fd, (struct sockaddr*)&sa, sizeof sa) != 0 ||
        listen(f->listen_fd, 4) != 0 || getsockname(f->listen_fd, (struct sockaddr*)&sa, &len)) {
        perror("fake manager: cannot listen");
        exit(2);
    }
    f->port = ntohs(sa.sin_port);
    snprintf(f->address, sizeof f->address, "127.0.0.1:%d", f->port);
    f->sessions = sessions;
    pthread_create(&f->thread, NULL, fake_main, f);
}

/* Joins the fake (it ends when its script does) and counts its failed checks as the test's. */
FAKE_FN void fake_stop(struct fake* f)
{
    pthread_join(f->thread, NULL);
    close(f->listen_fd);
    sem_destroy(&f->go);
    sem_destroy(&f->reached);
    ln_test_failures += f->errors;
}

/* Options for connecting to f with a generous timeout (tests never wait for it to pass). */
FAKE_FN ln_client_options fake_options(const struct fake* f)
{
    ln_client_options o;
    ln_client_options_init(&o);
    o.manager = f->address;
    o.timeout = 10;
    return o;
}

/* ln_client_create that is expected to succeed; prints the error if not. */
FAKE_FN ln_client* connect_ok(const char* name, const ln_client_options* o)
{
    ln_client* c = NULL;
    int rc = ln_client_create(&c, name, o);
    LN_CHECK_EQ(rc, LN_OK);
    if (rc != LN_OK)
        fprintf(stderr, "    %s\n", ln_last_error());
    return c;
}

/* The request most tests send. */
FAKE_FN int topic_info(ln_client* c, const char* topic, char* md, size_t size)
{
    ln_wbuf body;
    ln_wbuf_init(&body);
    ln_wbuf_str(&body, topic);
    uint16_t type = 0;
    ln_rbuf r;
    int rc = ln_client_request(c, LN_MSG_TOPIC_INFO, &body, &type, &r);
    ln_wbuf_free(&body);
    if (rc == LN_OK) {
        ln_rbuf_str(&r, md, size);
        LN_CHECK(ln_rbuf_u64(&r) == 0xfeedull);
        LN_CHECK_EQ(ln_rbuf_u32(&r), 64);
        LN_CHECK_EQ(ln_rbuf_u32(&r), 1);
        LN_CHECK_EQ(ln_rbuf_u32(&r), 2);
        LN_CHECK_EQ(ln_rbuf_end(&r), LN_OK);
        LN_CHECK_EQ(type, LN_MSG_TOPIC_INFO_OK);
    }
    return rc;
}

/* 1 if the thread's last error contains `part`; prints the text otherwise. */
FAKE_FN int error_has(const char* part)
{
    if (strstr(ln_last_error(), part) != NULL)
        return 1;
    fprintf(stderr, "    \"%s\" not in last error \"%s\"\n", part, ln_last_error());
    return 0;
}

#endif /* LN_FAKE_MANAGER_H */
