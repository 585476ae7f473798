/* test_client_request.c — ln_client_request against a scripted fake manager: answers and
 * ERROR answers, a manager that hangs up mid-request (without reconnection: the connection
 * stays lost; with it: the client comes back by itself), every kind of malformed answer,
 * timeouts (the late answer is skipped, a late PORT_OK is given back), and destroy while a
 * reconnect is stuck. */
#define _GNU_SOURCE 1 /* libln's own sources are built with it */

#include "fake_manager.h"

/* Starts f with `script` and connects; the handshake always succeeds. */
static ln_client* start(struct fake* f, void (*script)(struct fake*, int), int variant,
                        double timeout)
{
    fake_start(f, script, variant);
    ln_client_options o = fake_options(f);
    o.timeout = timeout;
    o.flags = LN_CLIENT_NO_RECONNECT;
    return connect_ok("req", &o);
}

static int welcomed(struct fake* f, int fd)
{
    if (!fake_hello(f, fd))
        return 0;
    fake_welcome(f, fd, LN_PROTO_VERSION, "req");
    return 1;
}

static void test_answers_and_errors(void)
{
    struct fake f;
    ln_client* c = start(&f, script_welcome, 0, 10);
    char md[64];
    if (c != NULL) {
        LN_CHECK_EQ(topic_info(c, "a.b", md, sizeof md), LN_OK);
        LN_CHECK_STREQ(md, "a.b");
        uint32_t first = c->conn.last_request_id;
        LN_CHECK_EQ(topic_info(c, "missing", md, sizeof md), LN_ENOTFOUND);
        LN_CHECK_STREQ(ln_last_error(), "topic 'missing' does not exist");
        LN_CHECK_EQ(c->last_code, LN_ENOTFOUND); /* the client keeps its own copy */
        LN_CHECK_STREQ(c->last_error, "topic 'missing' does not exist");
        LN_CHECK_EQ(topic_info(c, "c.d", md, sizeof md), LN_OK); /* still connected */
        LN_CHECK_STREQ(md, "c.d");
        LN_CHECK(c->conn.last_request_id == first + 2);
        ln_client_destroy(c);
    }
    fake_stop(&f);
    LN_CHECK(f.saw_eof);
}

static void test_body_that_failed_to_encode(void)
{
    struct fake f;
    ln_client* c = start(&f, script_welcome, 0, 10);
    if (c != NULL) {
        ln_wbuf body;
        ln_wbuf_init(&body);
        ln_wbuf_str(&body, "bad\xff");
        uint16_t type;
        ln_rbuf r;
        LN_CHECK_EQ(ln_client_request(c, LN_MSG_TOPIC_INFO, &body, &type, &r), LN_EINVAL);
        LN_CHECK(error_has("cannot encode TOPIC_INFO"));
        ln_wbuf_free(&body);
        char md[64];
        LN_CHECK_EQ(topic_info(c, "ok", md, sizeof md), LN_OK); /* nothing half-sent */
        ln_client_destroy(c);
    }
    fake_stop(&f);
}

/* Hangs up at a point chosen by f->variant. */
static void script_hang_up(struct fake* f, int fd)
{
    if (!welcomed(f, fd))
        return;
    char topic[64];
    if (f->variant == 0 || fake_topic_info(f, fd, topic, sizeof topic) == 0)
        return; /* 0: before the request arrives */
    if (f->variant == 2)
        fake_send_raw(fd, "\x20\x00", 2); /* part of a header */
    if (f->variant == 3)
        fake_send_raw(fd, "\x20\x00\x00\x00\x10\x00\x01", 7); /* header, part of a body */
}

static void test_manager_hangs_up(void)
{
    for (int variant = 0; variant <= 3; variant++) {
        struct fake f;
        ln_client* c = start(&f, script_hang_up, variant, 10);
        if (c == NULL) {
            fake_stop(&f);
            continue;
        }
        char md[64];
        LN_CHECK_EQ(topic_info(c, "a.b", md, sizeof md), LN_ECONNECTION);
        LN_CHECK(error_has("manager 127.0.0.1:"));
        fake_stop(&f);
        /* Stays disconnected, fails fast, and a dead peer never raised SIGPIPE. */
        LN_CHECK_EQ(topic_info(c, "a.b", md, sizeof md), LN_ECONNECTION);
        LN_CHECK(error_has("cannot send TOPIC_INFO: the connection to manager"));
        LN_CHECK(error_has("was lost earlier"));
        LN_CHECK_EQ(ln_client_destroy(c), LN_OK);
    }
}

/* Session 0 hangs up after one answer; session 1 (the "restarted manager") expects a
 * reconnecting HELLO and serves. */
static void script_restart(struct fake* f, int fd)
{
    if (!fake_hello(f, fd))
        return;
    FAKE_CHECK(f, f->hello_flags == (f->session ? LN_PROTO_HELLO_RECONNECT : 0u));
    fake_welcome(f, fd, LN_PROTO_VERSION, "req");
    char topic[64];
    uint32_t id = fake_topic_info(f, fd, topic, sizeof topic);
    if (id != 0)
        fake_topic_info_ok(f, fd, id, topic);
    if (f->session == 1)
        fake_serve(f, fd);
}

static void test_reconnects_after_hang_up(void)
{
    struct fake f;
    fake_start_sessions(&f, script_restart, 0, 2);
    ln_client_options o = fake_options(&f);
    ln_client* c = connect_ok("req", &o);
    char md[64];
    if (c != NULL) {
        LN_CHECK_EQ(topic_info(c, "a.b", md, sizeof md), LN_OK);
        /* The fake hangs up now; requests fail until the monitor is back, then work. */
        int rc;
        int lost = 0;
        while ((rc = topic_info(c, "c.d", md, sizeof md)) == LN_ECONNECTION) {
            lost = 1;
            LN_CHECK(error_has("manager 127.0.0.1:"));
            struct timespec pause = {0, 10000000};
            nanosleep(&pause, NULL);
        }
        LN_CHECK_EQ(rc, LN_OK);
        LN_CHECK_STREQ(md, "c.d");
        LN_CHECK(lost || f.session == 1);
        LN_CHECK_STREQ(ln_client_name(c), "req");
        LN_CHECK_EQ(ln_client_destroy(c), LN_OK);
    }
    fake_stop(&f);
    LN_CHECK_EQ(f.session, 2); /* both sessions ran */
}

/* Accepts, reads HELLO and never answers: a reconnect hangs in its handshake. */
static void script_mute(struct fake* f, int fd)
{
    if (f->session == 0) {
        if (fake_hello(f, fd))
            fake_welcome(f, fd, LN_PROTO_VERSION, "req");
        return; /* hang up: the client reconnects */
    }
    fake_hello(f, fd);
    sem_post(&f->reached);
    sem_wait(&f->go);
}

static void test_destroy_during_reconnect(void)
{
    struct fake f;
    fake_start_sessions(&f, script_mute, 0, 2);
    ln_client_options o = fake_options(&f);
    o.timeout = -1; /* the handshake would wait forever: only destroy can end it */
    ln_client* c = connect_ok("req", &o);
    if (c != NULL) {
        sem_wait(&f.reached);
        /* the client sent its reconnecting HELLO and waits for an answer that never comes */
        char md[64];
        LN_CHECK_EQ(topic_info(c, "a.b", md, sizeof md), LN_ECONNECTION);
        LN_CHECK_EQ(ln_client_destroy(c), LN_OK); /* returns: the reconnect was cut short */
    }
    sem_post(&f.go);
    fake_stop(&f);
}

/* Answers the first TOPIC_INFO with something malformed, chosen by f->variant. */
static void script_bad_answer(struct fake* f, int fd)
{
    char topic[64];
    uint32_t id;
    if (!welcomed(f, fd) || (id = fake_topic_info(f, fd, topic, sizeof topic)) == 0)
        return;
    ln_wbuf b;
    ln_wbuf_init(&b);
    int v = f->variant;
    if (v == 0) {
        fake_send_raw(fd, "GARBAGE GARBAGE GARBAGE", 23); /* length "GARB": far too big */
    } else if (v == 1) {
        fake_send_raw(fd, "\x01\x00\x00\x00\x10\x00", 6); /* length 1 */
    } else if (v == 2) {
        fake_send_raw(fd, "\x06\x00\x00\x00\x63\x00\x01\x00\x00\x00", 10); /* type 99 */
    } else if (v == 3) { /* OK where TOPIC_INFO_OK belongs */
        ln_proto_frame_begin(&b, LN_MSG_OK);
        ln_wbuf_u32(&b, id);
    } else if (v == 4 || v == 5 || v == 6) { /* trailing byte / missing field / bad UTF-8 */
        ln_proto_frame_begin(&b, LN_MSG_TOPIC_INFO_OK);
        ln_wbuf_u32(&b, id);
        if (v == 6) {
            ln_wbuf_u16(&b, 3);
            ln_wbuf_bytes(&b, "a\xed\xa0", 3);
        } else {
            ln_wbuf_str(&b, "x/y");
        }
        ln_wbuf_u64(&b, 0xfeed);
        ln_wbuf_u32(&b, 64);
        ln_wbuf_u32(&b, 1);
        if (v != 5)
            ln_wbuf_u32(&b, 2);
        if (v == 4)
            ln_wbuf_bytes(&b, "", 1);
    } else if (v == 7 || v == 8) { /* ERROR with bad UTF-8 / trailing bytes */
        ln_proto_frame_begin(&b, LN_MSG_ERROR);
        ln_wbuf_u32(&b, id);
        ln_wbuf_i32(&b, LN_ENOTFOUND);
        if (v == 7) {
            ln_wbuf_u16(&b, 1);
            ln_wbuf_bytes(&b, "\x80", 1);
        } else {
            ln_wbuf_str(&b, "fine");
            ln_wbuf_u32(&b, 0);
        }
    } else if (v == 9 || v == 10) { /* an id never sent / id 0 */
        ln_proto_frame_begin(&b, LN_MSG_OK);
        ln_wbuf_u32(&b, v == 9 ? id + 100 : 0);
    } else if (v == 11) { /* a frame only clients send */
        ln_proto_frame_begin(&b, LN_MSG_TOPIC_INFO);
        ln_wbuf_u32(&b, id);
        ln_wbuf_str(&b, "t");
    } else { /* a second WELCOME */
        ln_proto_frame_begin(&b, LN_MSG_WELCOME);
        ln_wbuf_u16(&b, LN_PROTO_VERSION);
        ln_wbuf_u32(&b, 1);
        ln_wbuf_str(&b, "a");
        ln_wbuf_str(&b, "b");
    }
    if (b.len > 0)
        fake_send(f, fd, &b);
    uint16_t type;
    ln_rbuf r;
    FAKE_CHECK(f, !fake_recv(f, fd, &type, &r)); /* the client hangs up */
}

static void test_malformed_answers(void)
{
    for (int variant = 0; variant <= 12; variant++) {
        struct fake f;
        ln_client* c = start(&f, script_bad_answer, variant, 10);
        if (c == NULL) {
            fake_stop(&f);
            continue;
        }
        char md[64];
        int rc = topic_info(c, "a.b", md, sizeof md);
        if (rc != LN_EPROTOCOL)
            fprintf(stderr, "    variant %d: %s\n", variant, ln_last_error());
        LN_CHECK_EQ(rc, LN_EPROTOCOL);
        LN_CHECK(error_has("malformed answer from manager 127.0.0.1:"));
        LN_CHECK(error_has("to TOPIC_INFO"));
        LN_CHECK(error_has("connection closed"));
        fake_stop(&f); /* returns once the fake saw the client hang up */
        LN_CHECK(f.saw_eof);
        LN_CHECK_EQ(topic_info(c, "a.b", md, sizeof md), LN_ECONNECTION);
        ln_client_destroy(c);
    }
}

/* ERROR codes outside the table: well-formed frames, so the connection stays. */
static void script_odd_codes(struct fake* f, int fd)
{
    char topic[64];
    uint32_t id;
    if (!welcomed(f, fd))
        return;
    const int32_t codes[] = {-LN_ERROR_COUNT - 1, 0, 7};
    for (size_t i = 0; i < LN_ARRAY_SIZE(codes); i++)
        if ((id = fake_topic_info(f, fd, topic, sizeof topic)) != 0)
            fake_error(f, fd, id, codes[i], "odd");
    fake_serve(f, fd);
}

static void test_unknown_error_codes(void)
{
    struct fake f;
    ln_client* c = start(&f, script_odd_codes, 0, 10);
    if (c != NULL) {
        char md[64];
        for (int i = 0; i < 3; i++) {
            LN_CHECK_EQ(topic_info(c, "a.b", md, sizeof md), LN_EPROTOCOL);
            LN_CHECK(error_has("with unknown code"));
        }
        LN_CHECK_EQ(topic_info(c, "a.b", md, sizeof md), LN_OK);
        ln_client_destroy(c);
    }
    fake_stop(&f);
}

/* The first answer comes only after the client gave up on it; then business as usual. */
static void script_late_answer(struct fake* f, int fd)
{
    char topic[64];
    uint32_t id;
    if (!welcomed(f, fd) || (id = fake_topic_info(f, fd, topic, sizeof topic)) == 0)
        return;
    sem_wait(&f->go);
    fake_topic_info_ok(f, fd, id, "late");
    fake_serve(f, fd);
}

static void test_timeout_then_late_answer_skipped(void)
{
    struct fake f;
    ln_client* c = start(&f, script_late_answer, 0, 0.2);
    if (c != NULL) {
        char md[64];
        LN_CHECK_EQ(topic_info(c, "first", md, sizeof md), LN_ETIMEOUT);
        LN_CHECK(error_has("no answer from manager 127.0.0.1:"));
        LN_CHECK(error_has("to TOPIC_INFO: timed out after 0.2 s"));
        LN_CHECK_EQ(c->conn.stale_answers, 1);
        sem_post(&f.go);
        LN_CHECK_EQ(topic_info(c, "second", md, sizeof md), LN_OK);
        LN_CHECK_STREQ(md, "second");
        LN_CHECK_EQ(c->conn.stale_answers, 0);
        ln_client_destroy(c);
    } else {
        sem_post(&f.go);
    }
    fake_stop(&f);
}

/* A PUBLISH answered only after the client gave up: the client must give the port back. */
static void script_late_port(struct fake* f, int fd)
{
    uint16_t type;
    ln_rbuf r;
    if (!welcomed(f, fd) || !fake_recv(f, fd, &type, &r))
        return;
    FAKE_CHECK(f, type == LN_MSG_PUBLISH);
    uint32_t id = ln_rbuf_u32(&r);
    sem_wait(&f->go);
    ln_wbuf b;
    ln_wbuf_init(&b);
    ln_proto_frame_begin(&b, LN_MSG_PORT_OK);
    ln_wbuf_u32(&b, id);
    ln_wbuf_u32(&b, 77);
    ln_wbuf_str(&b, "/ln.test.1.0");
    ln_wbuf_u32(&b, 0xFFFFFFFFu);
    fake_send(f, fd, &b);
    fake_serve(f, fd);
}

static void test_late_port_given_back(void)
{
    struct fake f;
    ln_client* c = start(&f, script_late_port, 0, 0.2);
    if (c != NULL) {
        ln_wbuf body;
        ln_wbuf_init(&body);
        ln_wbuf_str(&body, "a.b");
        ln_wbuf_str(&body, "x/y");
        ln_wbuf_u64(&body, 1);
        ln_wbuf_u32(&body, 8);
        ln_wbuf_u32(&body, 1);
        ln_wbuf_u32(&body, 0);
        uint16_t type;
        ln_rbuf r;
        LN_CHECK_EQ(ln_client_request(c, LN_MSG_PUBLISH, &body, &type, &r), LN_ETIMEOUT);
        ln_wbuf_free(&body);
        sem_post(&f.go);
        char md[64];
        /* skips the PORT_OK and sends CLOSE_PORT for it ... */
        LN_CHECK_EQ(topic_info(c, "x", md, sizeof md), LN_OK);
        LN_CHECK_STREQ(md, "x");
        /* ... whose OK the next request skips */
        LN_CHECK_EQ(topic_info(c, "y", md, sizeof md), LN_OK);
        LN_CHECK_STREQ(md, "y");
        ln_client_destroy(c);
    } else {
        sem_post(&f.go);
    }
    fake_stop(&f);
    LN_CHECK_EQ(f.closed_port, 77);
}

/* Half an answer, then silence: the stream is out of step, so the client must hang up. */
static void script_half_answer(struct fake* f, int fd)
{
    char topic[64];
    if (!welcomed(f, fd) || fake_topic_info(f, fd, topic, sizeof topic) == 0)
        return;
    fake_send_raw(fd, "\x20\x00\x00", 3);
    sem_wait(&f->go);
    uint16_t type;
    ln_rbuf r;
    FAKE_CHECK(f, !fake_recv(f, fd, &type, &r));
}

static void test_timeout_mid_answer_disconnects(void)
{
    struct fake f;
    ln_client* c = start(&f, script_half_answer, 0, 0.2);
    if (c != NULL) {
        char md[64];
        LN_CHECK_EQ(topic_info(c, "a.b", md, sizeof md), LN_ETIMEOUT);
        LN_CHECK(error_has("timed out after 0.2 s"));
        sem_post(&f.go);
        LN_CHECK_EQ(topic_info(c, "a.b", md, sizeof md), LN_ECONNECTION);
        ln_client_destroy(c);
    } else {
        sem_post(&f.go);
    }
    fake_stop(&f);
    LN_CHECK(f.saw_eof);
}

int main(void)
{
    LN_TEST_RUN(test_answers_and_errors);
    LN_TEST_RUN(test_body_that_failed_to_encode);
    LN_TEST_RUN(test_manager_hangs_up);
    LN_TEST_RUN(test_reconnects_after_hang_up);
    LN_TEST_RUN(test_destroy_during_reconnect);
    LN_TEST_RUN(test_malformed_answers);
    LN_TEST_RUN(test_unknown_error_codes);
    LN_TEST_RUN(test_timeout_then_late_answer_skipped);
    LN_TEST_RUN(test_late_port_given_back);
    LN_TEST_RUN(test_timeout_mid_answer_disconnects);
    LN_TEST_EXIT();
}
