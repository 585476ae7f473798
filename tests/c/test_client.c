/* test_client.c — creating and destroying clients against a scripted fake manager: the
 * HELLO/WELCOME handshake and each way it can fail, handle checks, ports closed by destroy,
 * and the per-thread last error.  Addresses and names: test_client_options.c. */
#define _GNU_SOURCE 1 /* libln's own sources are built with it */

#include "fake_manager.h"

/* Runs one create against a fake with `script` and returns its result; the client, if any,
 * is destroyed again. */
static int create_against(void (*script)(struct fake*, int), int variant, double timeout)
{
    struct fake f;
    fake_start(&f, script, variant);
    ln_client_options o = fake_options(&f);
    o.timeout = timeout;
    static struct ln_client sentinel;
    ln_client* c = &sentinel; /* must be reset to NULL on failure */
    int rc = ln_client_create(&c, "cam", &o);
    if (rc != LN_OK)
        LN_CHECK(c == NULL);
    else
        ln_client_destroy(c);
    sem_post(&f.go); /* for scripts that stall; the last error stays the create's */
    fake_stop(&f);
    return rc;
}

static void test_handshake(void)
{
    struct fake f;
    fake_start(&f, script_welcome, 0);
    ln_client_options o = fake_options(&f);
    ln_client* c = connect_ok("cam", &o);
    if (c != NULL) {
        LN_CHECK_STREQ(ln_client_name(c), "cam-2");
        LN_CHECK_STREQ(c->instance, "testinstance");
        LN_CHECK_EQ(c->client_id, 42);
        LN_CHECK_EQ(ln_client_pid(c), getpid());
        LN_CHECK_EQ(ln_client_check(c), LN_OK);
        LN_CHECK_EQ(ln_client_destroy(c), LN_OK);
    }
    fake_stop(&f);
    LN_CHECK_EQ(f.hello_magic, LN_PROTO_MAGIC);
    LN_CHECK_EQ(f.hello_version, LN_PROTO_VERSION);
    LN_CHECK_EQ(f.hello_pid, getpid());
    LN_CHECK_STREQ(f.hello_name, "cam");
    LN_CHECK_STREQ(f.hello_lib, ln_version());
    char host[LN_HOST_ID_MAX];
    ln_host_id(host, sizeof host);
    LN_CHECK(host[0] != '\0');
    LN_CHECK_STREQ(f.hello_host, host);
    LN_CHECK(f.saw_eof); /* destroy closed the connection */
}

static void test_hello_carries_host_id(void)
{
    char saved[LN_HOST_ID_MAX] = "";
    const char* env = getenv("LN_HOST_ID");
    if (env)
        snprintf(saved, sizeof saved, "%s", env);
    setenv("LN_HOST_ID", "rack-\xc3\xa4/7", 1);
    struct fake f;
    fake_start(&f, script_welcome, 0);
    ln_client_options o = fake_options(&f);
    ln_client* c = connect_ok("cam", &o);
    if (c != NULL)
        ln_client_destroy(c);
    fake_stop(&f);
    LN_CHECK_STREQ(f.hello_host, "rack-\xc3\xa4/7");
    /* Cut to the buffer, never inside a UTF-8 character (it must still encode). */
    char small[7];
    ln_host_id(small, sizeof small);
    LN_CHECK_STREQ(small, "rack-");
    char tiny[8];
    ln_host_id(tiny, sizeof tiny);
    LN_CHECK_STREQ(tiny, "rack-\xc3\xa4");
    ln_host_id(NULL, 10); /* no-op */
    ln_host_id(tiny, 0);
    LN_CHECK_STREQ(tiny, "rack-\xc3\xa4");
    /* Without the variable: hostname/boot_id, one line. */
    unsetenv("LN_HOST_ID");
    char host[LN_HOST_ID_MAX];
    ln_host_id(host, sizeof host);
    LN_CHECK(strchr(host, '/') != NULL && strchr(host, '\n') == NULL);
    if (saved[0])
        setenv("LN_HOST_ID", saved, 1);
}

static void script_refuse_version(struct fake* f, int fd)
{
    if (fake_hello(f, fd))
        fake_error(f, fd, 0, LN_EVERSION, "client speaks protocol 3, manager speaks 4");
}

static void script_welcome_next(struct fake* f, int fd)
{
    if (fake_hello(f, fd))
        fake_welcome(f, fd, LN_PROTO_VERSION + 1, "cam");
}

static void test_version_mismatch(void)
{
    LN_CHECK_EQ(create_against(script_refuse_version, 0, 10), LN_EVERSION);
    LN_CHECK(error_has("refused client \"cam\""));
    LN_CHECK(error_has("client speaks protocol 3, manager speaks 4"));
    /* The client notices a WELCOME it does not understand by itself. */
    LN_CHECK_EQ(LN_PROTO_VERSION, 3);
    LN_CHECK_EQ(create_against(script_welcome_next, 0, 10), LN_EVERSION);
    LN_CHECK(error_has("client speaks protocol 3, manager speaks 4"));
}

static void script_refuse_other(struct fake* f, int fd)
{
    if (fake_hello(f, fd))
        fake_error(f, fd, 0, LN_ELIMIT, "too many clients");
}

static void test_refused_with_other_code(void)
{
    LN_CHECK_EQ(create_against(script_refuse_other, 0, 10), LN_ELIMIT);
    LN_CHECK(error_has("too many clients"));
}

static void script_close_after_hello(struct fake* f, int fd) { fake_hello(f, fd); }

static void test_manager_closes_during_handshake(void)
{
    LN_CHECK_EQ(create_against(script_close_after_hello, 0, 10), LN_ECONNECTION);
    LN_CHECK(error_has("manager closed the connection"));
}

/* Answers HELLO with something malformed, chosen by f->variant. */
static void script_bad_welcome(struct fake* f, int fd)
{
    if (!fake_hello(f, fd))
        return;
    ln_wbuf b;
    ln_wbuf_init(&b);
    switch (f->variant) {
    case 0:
        fake_send_raw(fd, "HTTP/1.1 400 Bad Request\r\n\r\n", 28);
        break;
    case 1: /* trailing byte */
        ln_proto_frame_begin(&b, LN_MSG_WELCOME);
        ln_wbuf_u16(&b, LN_PROTO_VERSION);
        ln_wbuf_u32(&b, 1);
        ln_wbuf_str(&b, "cam");
        ln_wbuf_str(&b, "i");
        ln_wbuf_bytes(&b, "", 1);
        break;
    case 2: /* name not UTF-8 */
        ln_proto_frame_begin(&b, LN_MSG_WELCOME);
        ln_wbuf_u16(&b, LN_PROTO_VERSION);
        ln_wbuf_u32(&b, 1);
        ln_wbuf_u16(&b, 2);
        ln_wbuf_bytes(&b, "\xc0\x80", 2);
        ln_wbuf_str(&b, "i");
        break;
    case 3: /* an answer to a request that was never made */
        ln_proto_frame_begin(&b, LN_MSG_OK);
        ln_wbuf_u32(&b, 0);
        break;
    case 4: /* ERROR with a request id */
        ln_proto_frame_begin(&b, LN_MSG_ERROR);
        ln_wbuf_u32(&b, 5);
        ln_wbuf_i32(&b, LN_EVERSION);
        ln_wbuf_str(&b, "x");
        break;
    case 5: /* empty name */
        ln_proto_frame_begin(&b, LN_MSG_WELCOME);
        ln_wbuf_u16(&b, LN_PROTO_VERSION);
        ln_wbuf_u32(&b, 1);
        ln_wbuf_str(&b, "");
        ln_wbuf_str(&b, "i");
        break;
    default: /* a frame type the client would send */
        ln_proto_frame_begin(&b, LN_MSG_TOPIC_INFO);
        ln_wbuf_u32(&b, 1);
        ln_wbuf_str(&b, "t");
        break;
    }
    if (b.len > 0)
        fake_send(f, fd, &b);
    uint16_t type;
    ln_rbuf r;
    FAKE_CHECK(f, !fake_recv(f, fd, &type, &r)); /* the client hangs up */
}

static void test_malformed_welcome(void)
{
    for (int variant = 0; variant <= 6; variant++) {
        LN_CHECK_EQ(create_against(script_bad_welcome, variant, 10), LN_EPROTOCOL);
        LN_CHECK(error_has("malformed answer from manager 127.0.0.1:"));
    }
}

static void script_stall(struct fake* f, int fd)
{
    if (fake_hello(f, fd))
        sem_wait(&f->go); /* until the client has given up */
}

static void test_handshake_timeout(void)
{
    LN_CHECK_EQ(create_against(script_stall, 0, 0.2), LN_ETIMEOUT);
    LN_CHECK(error_has("no answer from manager 127.0.0.1:"));
    LN_CHECK(error_has("timed out after 0.2 s"));
}
static void test_bad_handles(void)
{
    LN_CHECK_EQ(ln_client_destroy(NULL), LN_OK);
    LN_CHECK(ln_client_name(NULL) == NULL);
    LN_CHECK(error_has("invalid client handle"));
    struct ln_client zeroed;
    memset(&zeroed, 0, sizeof zeroed);
    LN_CHECK_EQ(ln_client_check(&zeroed), LN_EBADHANDLE);
    LN_CHECK_EQ(ln_client_destroy(&zeroed), LN_EBADHANDLE);
    LN_CHECK(ln_client_name(&zeroed) == NULL);
    uint16_t type;
    ln_rbuf r;
    LN_CHECK_EQ(ln_client_request(NULL, LN_MSG_TOPIC_INFO, NULL, &type, &r), LN_EBADHANDLE);
}

/* Ports: destroy closes what is left, newest first, through each port's close_fn. */
static ln_client* port_owner;
static int closed[8], nclosed;

static void close_port(void* port)
{
    closed[nclosed++] = *(int*)port;
    ln_client_remove_port(port_owner, port);
}

static void close_port_forgetful(void* port)
{
    closed[nclosed++] = *(int*)port; /* breaks the contract: does not remove itself */
}

static int reclaim_nothing(ln_client* clnt, void* port)
{
    (void)clnt;
    (void)port;
    return LN_OK;
}

static const ln_client_port_ops port_ops = {close_port, reclaim_nothing};
static const ln_client_port_ops forgetful_ops = {close_port_forgetful, reclaim_nothing};

static void test_destroy_closes_ports(void)
{
    struct fake f;
    fake_start(&f, script_welcome, 0);
    ln_client_options o = fake_options(&f);
    ln_client* c = connect_ok("cam", &o);
    if (c != NULL) {
        static int ids[] = {1, 2, 3, 4};
        port_owner = c;
        nclosed = 0;
        LN_CHECK_EQ(ln_client_add_port(c, &ids[0], &forgetful_ops, 1), LN_OK);
        for (int i = 1; i < 4; i++)
            LN_CHECK_EQ(ln_client_add_port(c, &ids[i], &port_ops, 1), LN_OK);
        ln_client_remove_port(c, &ids[2]); /* closed by its owner already */
        ln_client_remove_port(c, &ids[2]); /* twice is harmless */
        LN_CHECK_EQ(ln_client_destroy(c), LN_OK);
        LN_CHECK_EQ(nclosed, 3);
        LN_CHECK_EQ(closed[0], 4);
        LN_CHECK_EQ(closed[1], 2);
        LN_CHECK_EQ(closed[2], 1);
    }
    fake_stop(&f);
}

static void* set_other_error(void* arg)
{
    (void)arg;
    ln_set_error(NULL, LN_EBUSY, "error of another thread");
    return NULL;
}

static void test_last_error_per_thread(void)
{
    LN_CHECK_EQ(ln_set_error(NULL, LN_EINVAL, "first %d", 1), LN_EINVAL);
    pthread_t t;
    pthread_create(&t, NULL, set_other_error, NULL);
    pthread_join(t, NULL);
    LN_CHECK_STREQ(ln_last_error(), "first 1");
    /* context in front of an earlier error, from the very buffer being written */
    ln_set_error(NULL, LN_EINVAL, "while testing: %s", ln_last_error());
    LN_CHECK_STREQ(ln_last_error(), "while testing: first 1");
    errno = 1234;
    LN_CHECK_EQ(ln_set_errno_error(NULL, ECONNREFUSED, "connect %s", "x"), LN_ECONNECTION);
    LN_CHECK_STREQ(ln_last_error(), "connect x: Connection refused");
    LN_CHECK_EQ(errno, 1234);
    LN_CHECK_EQ(ln_errno_to_code(ENOMEM), LN_ENOMEM);
    LN_CHECK_EQ(ln_errno_to_code(EACCES), LN_EPERM);
    LN_CHECK_EQ(ln_errno_to_code(EPERM), LN_EPERM);
    LN_CHECK_EQ(ln_errno_to_code(ETIMEDOUT), LN_ETIMEOUT);
    LN_CHECK_EQ(ln_errno_to_code(EPIPE), LN_ECONNECTION);
    LN_CHECK_EQ(ln_errno_to_code(ECONNRESET), LN_ECONNECTION);
    LN_CHECK_EQ(ln_errno_to_code(ENOTCONN), LN_ECONNECTION);
    LN_CHECK_EQ(ln_errno_to_code(EINTR), LN_EINTR);
    LN_CHECK_EQ(ln_errno_to_code(EBADF), LN_ESYS);
    /* A text longer than the buffer is cut, not overflowed. */
    char big[3 * LN_ERROR_TEXT_MAX];
    memset(big, 'z', sizeof big - 1);
    big[sizeof big - 1] = '\0';
    ln_set_error(NULL, LN_EINVAL, "%s", big);
    LN_CHECK_EQ(strlen(ln_last_error()), LN_ERROR_TEXT_MAX - 1);
}

int main(void)
{
    LN_TEST_RUN(test_handshake);
    LN_TEST_RUN(test_hello_carries_host_id);
    LN_TEST_RUN(test_version_mismatch);
    LN_TEST_RUN(test_refused_with_other_code);
    LN_TEST_RUN(test_manager_closes_during_handshake);
    LN_TEST_RUN(test_malformed_welcome);
    LN_TEST_RUN(test_handshake_timeout);
    LN_TEST_RUN(test_bad_handles);
    LN_TEST_RUN(test_destroy_closes_ports);
    LN_TEST_RUN(test_last_error_per_thread);
    LN_TEST_EXIT();
}
