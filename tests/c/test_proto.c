/* test_proto.c — the manager protocol codec on byte strings: exact little-endian encoding,
 * round trips of every field type, and rejection of every malformed input of
 * docs/protocol.md (truncation, oversized length, unknown type, bad UTF-8, trailing bytes). */
#define _GNU_SOURCE 1 /* libln's own sources are built with it */

#include <stdlib.h>

/* The codec is internal (hidden in libln.so), so the test compiles it in. */
#include "../../libln/src/proto.c"
#include "client_wire.c" /* generated into the build tree from client.schema */

#include "ln_test.h"

static int bytes_equal(const ln_wbuf* b, const char* expected, size_t n)
{
    return b->len == n && memcmp(b->data, expected, n) == 0;
}

static void test_integers(void)
{
    ln_wbuf b;
    ln_wbuf_init(&b);
    ln_wbuf_u16(&b, 0x0102);
    ln_wbuf_u32(&b, 0x03040506);
    ln_wbuf_u64(&b, 0x0708090a0b0c0d0eull);
    ln_wbuf_i32(&b, -2);
    LN_CHECK(bytes_equal(&b,
                         "\x02\x01\x06\x05\x04\x03\x0e\x0d\x0c\x0b\x0a\x09\x08\x07"
                         "\xfe\xff\xff\xff",
                         18));
    ln_rbuf r;
    ln_rbuf_init(&r, b.data, b.len);
    LN_CHECK_EQ(ln_rbuf_u16(&r), 0x0102);
    LN_CHECK_EQ(ln_rbuf_u32(&r), 0x03040506);
    LN_CHECK(ln_rbuf_u64(&r) == 0x0708090a0b0c0d0eull);
    LN_CHECK_EQ(ln_rbuf_i32(&r), -2);
    LN_CHECK_EQ(ln_rbuf_end(&r), LN_OK);
    ln_wbuf_reset(&b); /* the extremes */
    ln_wbuf_u16(&b, UINT16_MAX);
    ln_wbuf_u32(&b, UINT32_MAX);
    ln_wbuf_u64(&b, UINT64_MAX);
    ln_wbuf_i32(&b, INT32_MIN);
    ln_rbuf_init(&r, b.data, b.len);
    LN_CHECK_EQ(ln_rbuf_u16(&r), UINT16_MAX);
    LN_CHECK(ln_rbuf_u32(&r) == UINT32_MAX);
    LN_CHECK(ln_rbuf_u64(&r) == UINT64_MAX);
    LN_CHECK_EQ(ln_rbuf_i32(&r), INT32_MIN);
    LN_CHECK_EQ(ln_rbuf_end(&r), LN_OK);
    ln_wbuf_free(&b);
    ln_wbuf_free(&b); /* twice is harmless */
}

static void test_strings_round_trip(void)
{
    char longest[LN_PROTO_MAX_STR + 1];
    memset(longest, 'x', LN_PROTO_MAX_STR);
    longest[LN_PROTO_MAX_STR] = '\0';
    const char* texts[] = {"",
                           "a",
                           "robot.joint_state",
                           "h\xc3\xa9llo \xe2\x82\xac \xf0\x9d\x84\x9e",
                           "\xf4\x8f\xbf\xbf\xed\x9f\xbf\xee\x80\x80", /* U+10FFFF U+D7FF U+E000 */
                           longest};
    for (size_t i = 0; i < LN_ARRAY_SIZE(texts); i++) {
        ln_wbuf b;
        ln_wbuf_init(&b);
        ln_wbuf_str(&b, texts[i]);
        LN_CHECK_EQ(b.failed, 0);
        LN_CHECK_EQ(b.len, 2 + strlen(texts[i]));
        char out[LN_PROTO_MAX_STR + 1];
        ln_rbuf r;
        ln_rbuf_init(&r, b.data, b.len);
        ln_rbuf_str(&r, out, sizeof out);
        LN_CHECK_STREQ(out, texts[i]);
        LN_CHECK_EQ(ln_rbuf_end(&r), LN_OK);
        ln_wbuf_free(&b);
    }
}

static void test_string_limits(void)
{
    char over[LN_PROTO_MAX_STR + 2];
    memset(over, 'y', sizeof over - 1);
    over[sizeof over - 1] = '\0';
    ln_wbuf b;
    ln_wbuf_init(&b);
    ln_wbuf_str(&b, over);
    LN_CHECK_EQ(b.failed, LN_EINVAL);
    ln_wbuf_u32(&b, 1); /* ignored once failed */
    LN_CHECK_EQ(b.len, 0);
    ln_wbuf_reset(&b);
    ln_wbuf_str(&b, NULL);
    LN_CHECK_EQ(b.failed, LN_EINVAL);

    /* A str field of 1025 bytes on the wire, although the bytes are there. */
    ln_wbuf_reset(&b);
    ln_wbuf_u16(&b, LN_PROTO_MAX_STR + 1);
    ln_wbuf_bytes(&b, over, LN_PROTO_MAX_STR + 1);
    char out[2 * LN_PROTO_MAX_STR];
    ln_rbuf r;
    ln_rbuf_init(&r, b.data, b.len);
    ln_rbuf_str(&r, out, sizeof out);
    LN_CHECK(r.failed);
    LN_CHECK_STREQ(out, "");

    /* Fits on the wire but not in the caller's buffer (which needs room for the NUL). */
    ln_wbuf_reset(&b);
    ln_wbuf_str(&b, "abcd");
    char small[4];
    ln_rbuf_init(&r, b.data, b.len);
    ln_rbuf_str(&r, small, sizeof small);
    LN_CHECK(r.failed);
    LN_CHECK_STREQ(small, "");
    char exact[5];
    ln_rbuf_init(&r, b.data, b.len);
    ln_rbuf_str(&r, exact, sizeof exact);
    LN_CHECK_STREQ(exact, "abcd");
    LN_CHECK_EQ(ln_rbuf_end(&r), LN_OK);
    ln_wbuf_free(&b);
}

static void test_bad_utf8_rejected(void)
{
    static const struct {
        const char* bytes;
        size_t len;
    } bad[] = {
        {"\x80", 1},             /* lone continuation byte */
        {"\xc0\x80", 2},         /* overlong NUL */
        {"\xc1\xbf", 2},         /* overlong ASCII */
        {"\xe0\x80\xaf", 3},     /* overlong 3-byte */
        {"\xf0\x80\x80\xaf", 4}, /* overlong 4-byte */
        {"\xed\xa0\x80", 3},     /* UTF-16 surrogate U+D800 */
        {"\xed\xbf\xbf", 3},     /* surrogate U+DFFF */
        {"\xf4\x90\x80\x80", 4}, /* U+110000 */
        {"\xf5\x80\x80\x80", 4}, /* lead byte beyond U+10FFFF */
        {"\xff", 1},
        {"\xe2\x82", 2},     /* truncated sequence */
        {"ok\xe2\x82", 4},   /* truncated at the end of the field */
        {"\xe2\x28\xa1", 3}, /* bad continuation */
        {"a\0b", 3},         /* NUL: valid UTF-8 but never in a str */
    };
    for (size_t i = 0; i < LN_ARRAY_SIZE(bad); i++) {
        ln_wbuf b;
        ln_wbuf_init(&b);
        ln_wbuf_u16(&b, (uint16_t)bad[i].len);
        ln_wbuf_bytes(&b, bad[i].bytes, bad[i].len);
        char out[16];
        ln_rbuf r;
        ln_rbuf_init(&r, b.data, b.len);
        ln_rbuf_str(&r, out, sizeof out);
        if (!r.failed)
            fprintf(stderr, "    accepted bad string #%zu\n", i);
        LN_CHECK(r.failed);
        LN_CHECK_EQ(ln_rbuf_end(&r), LN_EPROTOCOL);
        LN_CHECK_STREQ(out, "");
        /* The writer refuses what the reader would refuse (the NUL case cannot be written). */
        if (memchr(bad[i].bytes, '\0', bad[i].len) == NULL) {
            LN_CHECK(!ln_utf8_valid(bad[i].bytes, bad[i].len));
            char copy[16];
            memcpy(copy, bad[i].bytes, bad[i].len);
            copy[bad[i].len] = '\0';
            ln_wbuf_reset(&b);
            ln_wbuf_str(&b, copy);
            LN_CHECK_EQ(b.failed, LN_EINVAL);
        }
        ln_wbuf_free(&b);
    }
}

static void test_reading_past_end(void)
{
    static const uint8_t three[3] = {1, 2, 3};
    ln_rbuf r;
    ln_rbuf_init(&r, three, sizeof three);
    LN_CHECK_EQ(ln_rbuf_u16(&r), 0x0201);
    LN_CHECK_EQ(ln_rbuf_u16(&r), 0); /* one byte left: fails, yields 0 */
    LN_CHECK(r.failed);
    LN_CHECK_EQ(ln_rbuf_end(&r), LN_EPROTOCOL);
    ln_rbuf_init(&r, three, 1);
    LN_CHECK_EQ(ln_rbuf_u64(&r), 0);
    char out[8] = "junk";
    ln_rbuf_str(&r, out, sizeof out); /* still failed: "" */
    LN_CHECK_STREQ(out, "");
    ln_rbuf_init(&r, three, 0);
    LN_CHECK_EQ(ln_rbuf_end(&r), LN_OK); /* an empty body read completely */
}

/* PUBLISH as port.c sends it; the reference bytes are the layout of docs/protocol.md. */
static void build_publish(ln_wbuf* b)
{
    size_t start = ln_proto_frame_begin(b, LN_MSG_PUBLISH);
    ln_wbuf_u32(b, 7);
    ln_wbuf_str(b, "a.b");
    ln_wbuf_str(b, "x/y");
    ln_wbuf_u64(b, 0x1122334455667788ull);
    ln_wbuf_u32(b, 64);
    ln_wbuf_u32(b, 1);
    ln_wbuf_u32(b, 0);
    LN_CHECK_EQ(ln_proto_frame_end(b, start), LN_OK);
}

static const char publish_bytes[] = "\x24\x00\x00\x00"
                                    "\x0a\x00"         /* length 36, type 10 */
                                    "\x07\x00\x00\x00" /* request id */
                                    "\x03\x00"
                                    "a.b"
                                    "\x03\x00"
                                    "x/y"                              /* topic, md_name */
                                    "\x88\x77\x66\x55\x44\x33\x22\x11" /* layout hash */
                                    "\x40\x00\x00\x00"
                                    "\x01\x00\x00\x00"
                                    "\x00\x00\x00\x00";
#define PUBLISH_LEN (sizeof publish_bytes - 1)

/* Parses a PUBLISH body completely: LN_OK or LN_EPROTOCOL. */
static int parse_publish(ln_rbuf* r)
{
    char topic[256], md[256];
    int ok = ln_rbuf_u32(r) == 7;
    ln_rbuf_str(r, topic, sizeof topic);
    ln_rbuf_str(r, md, sizeof md);
    ok = ok && ln_rbuf_u64(r) == 0x1122334455667788ull;
    ok = ok && ln_rbuf_u32(r) == 64 && ln_rbuf_u32(r) == 1 && ln_rbuf_u32(r) == 0;
    int rc = ln_rbuf_end(r);
    if (rc == LN_OK && (!ok || strcmp(topic, "a.b") != 0 || strcmp(md, "x/y") != 0))
        return LN_EINVAL; /* parsed but wrong values: the test fails on it */
    return rc;
}

static void test_frame_encoding_and_round_trip(void)
{
    ln_wbuf b;
    ln_wbuf_init(&b);
    build_publish(&b);
    LN_CHECK(bytes_equal(&b, publish_bytes, PUBLISH_LEN));
    uint16_t type = 0;
    ln_rbuf body;
    LN_CHECK_EQ(ln_proto_decode_frame(b.data, b.len, &type, &body), LN_OK);
    LN_CHECK_EQ(type, LN_MSG_PUBLISH);
    LN_CHECK_EQ(parse_publish(&body), LN_OK);

    /* Two frames back to back in one buffer each get their own length. */
    size_t second = b.len;
    size_t start = ln_proto_frame_begin(&b, LN_MSG_OK);
    LN_CHECK_EQ(start, second);
    ln_wbuf_u32(&b, 0x01020304);
    LN_CHECK_EQ(ln_proto_frame_end(&b, start), LN_OK);
    LN_CHECK_EQ(b.len - second, 10);
    LN_CHECK(memcmp(b.data + second, "\x06\x00\x00\x00\x0e\x00\x04\x03\x02\x01", 10) == 0);
    LN_CHECK(memcmp(b.data, publish_bytes, PUBLISH_LEN) == 0);
    ln_wbuf_free(&b);
}

static void test_every_truncation_rejected(void)
{
    for (size_t len = 0; len < PUBLISH_LEN; len++) {
        uint16_t type;
        ln_rbuf body;
        LN_CHECK_EQ(ln_proto_decode_frame(publish_bytes, len, &type, &body), LN_EPROTOCOL);
    }
    /* A body cut short with a header that agrees (the manager never sends this, but a frame
     * is judged by its fields, not by its length alone). */
    for (size_t cut = 1; cut <= PUBLISH_LEN - LN_PROTO_HEADER_SIZE; cut++) {
        uint8_t frame[PUBLISH_LEN];
        size_t len = PUBLISH_LEN - cut;
        memcpy(frame, publish_bytes, len);
        put_le(frame, len - 4, 4);
        uint16_t type;
        ln_rbuf body;
        int rc = ln_proto_decode_frame(frame, len, &type, &body);
        if (rc == LN_OK)
            rc = parse_publish(&body);
        LN_CHECK_EQ(rc, LN_EPROTOCOL);
    }
}

static void test_trailing_bytes_rejected(void)
{
    uint8_t frame[PUBLISH_LEN + 1];
    memcpy(frame, publish_bytes, PUBLISH_LEN);
    frame[PUBLISH_LEN] = 0;
    uint16_t type;
    ln_rbuf body;
    /* after the frame */
    LN_CHECK_EQ(ln_proto_decode_frame(frame, sizeof frame, &type, &body), LN_EPROTOCOL);
    /* inside the frame, after the last field */
    put_le(frame, PUBLISH_LEN + 1 - 4, 4);
    LN_CHECK_EQ(ln_proto_decode_frame(frame, sizeof frame, &type, &body), LN_OK);
    LN_CHECK_EQ(parse_publish(&body), LN_EPROTOCOL);
}

static void test_header_bounds(void)
{
    static const struct {
        uint32_t length;
        uint16_t type;
        int rc;
    } cases[] = {
        {0, LN_MSG_OK, LN_EPROTOCOL},
        {1, LN_MSG_OK, LN_EPROTOCOL},
        {2, LN_MSG_OK, LN_OK}, /* type only, empty body: valid at frame level */
        {LN_PROTO_MAX_FRAME, LN_MSG_OK, LN_OK},
        {LN_PROTO_MAX_FRAME + 1, LN_MSG_OK, LN_EPROTOCOL},
        {UINT32_MAX, LN_MSG_OK, LN_EPROTOCOL},
        {6, 0, LN_EPROTOCOL},
        {6, 7, LN_EPROTOCOL}, /* 4..6 are the admission messages */
        {6, 9, LN_EPROTOCOL},
        {6, 18, LN_EPROTOCOL},
        {6, UINT16_MAX, LN_EPROTOCOL},
    };
    for (size_t i = 0; i < LN_ARRAY_SIZE(cases); i++) {
        uint8_t header[LN_PROTO_HEADER_SIZE];
        put_le(header, cases[i].length, 4);
        put_le(header + 4, cases[i].type, 2);
        uint32_t body_len = 12345;
        uint16_t type = 0;
        LN_CHECK_EQ(ln_proto_parse_header(header, &body_len, &type), cases[i].rc);
        if (cases[i].rc == LN_OK) {
            LN_CHECK_EQ(body_len, cases[i].length - 2);
            LN_CHECK_EQ(type, cases[i].type);
        }
    }
}

static void test_oversized_frame_not_encoded(void)
{
    ln_wbuf b;
    ln_wbuf_init(&b);
    size_t start = ln_proto_frame_begin(&b, LN_MSG_OK);
    uint8_t* big = calloc(1, LN_PROTO_MAX_FRAME);
    LN_CHECK(big != NULL);
    if (big == NULL)
        return;
    ln_wbuf_bytes(&b, big, LN_PROTO_MAX_FRAME - 2); /* length exactly the maximum */
    LN_CHECK_EQ(ln_proto_frame_end(&b, start), LN_OK);
    ln_wbuf_reset(&b);
    start = ln_proto_frame_begin(&b, LN_MSG_OK);
    ln_wbuf_bytes(&b, big, LN_PROTO_MAX_FRAME - 1);
    LN_CHECK_EQ(ln_proto_frame_end(&b, start), LN_ETOOBIG);
    free(big);
    ln_wbuf_free(&b);
}

static void test_message_types(void)
{
    LN_CHECK_EQ(ln_proto_answer_type(LN_MSG_PUBLISH), LN_MSG_PORT_OK);
    LN_CHECK_EQ(ln_proto_answer_type(LN_MSG_SUBSCRIBE), LN_MSG_PORT_OK);
    LN_CHECK_EQ(ln_proto_answer_type(LN_MSG_CLOSE_PORT), LN_MSG_OK);
    LN_CHECK_EQ(ln_proto_answer_type(LN_MSG_TOPIC_INFO), LN_MSG_TOPIC_INFO_OK);
    LN_CHECK_EQ(ln_proto_answer_type(LN_MSG_HELLO), 0); /* no request id */
    LN_CHECK_EQ(ln_proto_answer_type(LN_MSG_OK), 0);
    LN_CHECK_EQ(ln_proto_answer_type(99), 0);
    LN_CHECK_STREQ(ln_proto_type_name(LN_MSG_TOPIC_INFO_OK), "TOPIC_INFO_OK");
    LN_CHECK_STREQ(ln_proto_type_name(99), "UNKNOWN");
    int known = 0;
    for (uint32_t t = 0; t <= UINT16_MAX; t++)
        known += ln_proto_type_known((uint16_t)t);
    LN_CHECK_EQ(known, 24);
    LN_CHECK_EQ(ln_proto_answer_type(LN_MSG_RECLAIM_PORT), LN_MSG_PORT_OK);
    LN_CHECK_STREQ(ln_proto_type_name(LN_MSG_RECLAIM_PORT), "RECLAIM_PORT");
    LN_CHECK_EQ(ln_proto_answer_type(LN_MSG_REGISTER_SERVICE), LN_MSG_OK);
    LN_CHECK_EQ(ln_proto_answer_type(LN_MSG_UNREGISTER_SERVICE), LN_MSG_OK);
    LN_CHECK_EQ(ln_proto_answer_type(LN_MSG_FIND_SERVICE), LN_MSG_SERVICE_INFO);
    LN_CHECK_EQ(ln_proto_answer_type(LN_MSG_SERVICE_CALLED), LN_MSG_OK);
    LN_CHECK(ln_proto_to_client(LN_MSG_SERVICE_INFO) && !ln_proto_to_client(LN_MSG_FIND_SERVICE));
    LN_CHECK_EQ(ln_proto_answer_type(LN_MSG_CONTROL), LN_MSG_CONTROL_RESULT);
    LN_CHECK(ln_proto_to_client(LN_MSG_CONTROL_RESULT) && !ln_proto_to_client(LN_MSG_CONTROL));
    LN_CHECK_EQ(ln_proto_answer_type(LN_MSG_LOG), LN_MSG_OK);
    LN_CHECK(!ln_proto_to_client(LN_MSG_LOG));
    LN_CHECK(ln_proto_to_client(LN_MSG_CHALLENGE) && ln_proto_to_client(LN_MSG_AUTH_OK));
    LN_CHECK(!ln_proto_to_client(LN_MSG_AUTH));
    LN_CHECK_EQ(ln_proto_answer_type(LN_MSG_AUTH), 0); /* no request id, like HELLO */
    LN_CHECK_EQ(ln_proto_answer_type(LN_MSG_SERVICE_KEY), LN_MSG_SERVICE_KEY_INFO);
    LN_CHECK(ln_proto_to_client(LN_MSG_SERVICE_KEY_INFO) &&
             !ln_proto_to_client(LN_MSG_SERVICE_KEY));
}

static void test_text_fields(void)
{
    ln_wbuf b;
    ln_wbuf_init(&b);
    ln_wbuf_u32(&b, 7); /* request id */
    ln_wbuf_text(&b, "{\"op\": \"status\"}");
    LN_CHECK(bytes_equal(&b, "\x07\0\0\0\x10\0\0\0{\"op\": \"status\"}", 24));
    ln_rbuf r;
    ln_rbuf_init(&r, b.data, b.len);
    LN_CHECK_EQ(ln_proto_check_fields(LN_MSG_CONTROL, &r), LN_OK);
    ln_rbuf_u32(&r);
    size_t n;
    const char* text = ln_rbuf_text(&r, &n);
    LN_CHECK(text != NULL && n == 16 && memcmp(text, "{\"op\": \"status\"}", 16) == 0);
    LN_CHECK_EQ(ln_rbuf_end(&r), LN_OK);
    ln_rbuf_init(&r, b.data, b.len - 1); /* truncated */
    LN_CHECK_EQ(ln_proto_check_fields(LN_MSG_CONTROL, &r), LN_EPROTOCOL);
    ln_wbuf_reset(&b);
    ln_wbuf_u32(&b, 7);
    ln_wbuf_u32(&b, 3);
    ln_wbuf_bytes(&b, "a\0b", 3); /* NUL inside */
    ln_rbuf_init(&r, b.data, b.len);
    LN_CHECK_EQ(ln_proto_check_fields(LN_MSG_CONTROL_RESULT, &r), LN_EPROTOCOL);
    ln_wbuf_reset(&b);
    ln_wbuf_text(&b, "\xff"); /* not UTF-8: nothing written */
    LN_CHECK_EQ(b.failed, LN_EINVAL);
    ln_wbuf_free(&b);
}

/* A protocol-3 HELLO by hand: magic, version, pid, client name, libln version, host id,
 * flags. */
static const char hello_bytes[] = "\x21\x00\x00\x00"
                                  "\x01\x00" /* length 33, type 1 */
                                  "\x4c\x4e\x4d\x50"
                                  "\x03\x00"         /* "LNMP", version 3 */
                                  "\x39\x30\x00\x00" /* pid 12345 */
                                  "\x03\x00"
                                  "cam"
                                  "\x05\x00"
                                  "0.1.0" /* client name, libln version */
                                  "\x03\x00"
                                  "h/1"               /* host id */
                                  "\x01\x00\x00\x00"; /* flags: LN_PROTO_HELLO_RECONNECT */
#define HELLO_LEN (sizeof hello_bytes - 1)

static void test_hello_has_host_id(void)
{
    ln_wbuf b;
    ln_wbuf_init(&b);
    size_t start = ln_proto_frame_begin(&b, LN_MSG_HELLO);
    ln_wbuf_u32(&b, LN_PROTO_MAGIC);
    ln_wbuf_u16(&b, LN_PROTO_VERSION);
    ln_wbuf_u32(&b, 12345);
    ln_wbuf_str(&b, "cam");
    ln_wbuf_str(&b, "0.1.0");
    ln_wbuf_str(&b, "h/1");
    ln_wbuf_u32(&b, LN_PROTO_HELLO_RECONNECT);
    LN_CHECK_EQ(ln_proto_frame_end(&b, start), LN_OK);
    LN_CHECK(bytes_equal(&b, hello_bytes, HELLO_LEN));
    uint16_t type = 0;
    ln_rbuf body;
    LN_CHECK_EQ(ln_proto_decode_frame(b.data, b.len, &type, &body), LN_OK);
    LN_CHECK_EQ(type, LN_MSG_HELLO);
    LN_CHECK_EQ(ln_proto_check_fields(LN_MSG_HELLO, &body), LN_OK);
    /* A protocol-2 HELLO (no flags) does not have HELLO's fields any more. */
    ln_rbuf old = body;
    old.left -= 4;
    LN_CHECK_EQ(ln_proto_check_fields(LN_MSG_HELLO, &old), LN_EPROTOCOL);
    ln_wbuf_free(&b);
}

static void test_check_fields(void)
{
    /* PUBLISH from the reference bytes, then every shortening and one byte too many. */
    uint16_t type = 0;
    ln_rbuf body = {NULL, 0, 0};
    LN_CHECK_EQ(ln_proto_decode_frame(publish_bytes, PUBLISH_LEN, &type, &body), LN_OK);
    LN_CHECK_EQ(ln_proto_check_fields(LN_MSG_PUBLISH, &body), LN_OK);
    LN_CHECK_EQ(body.left, PUBLISH_LEN - LN_PROTO_HEADER_SIZE); /* the reader did not move */
    LN_CHECK_EQ(ln_proto_check_fields(LN_MSG_SUBSCRIBE, &body), LN_OK);
    LN_CHECK_EQ(ln_proto_check_fields(LN_MSG_TOPIC_INFO_OK, &body), LN_EPROTOCOL);
    LN_CHECK_EQ(ln_proto_check_fields(99, &body), LN_EPROTOCOL);
    for (size_t n = 0; n < body.left; n++) {
        ln_rbuf cut = body;
        cut.left = n;
        LN_CHECK_EQ(ln_proto_check_fields(LN_MSG_PUBLISH, &cut), LN_EPROTOCOL);
    }
    uint8_t longer[PUBLISH_LEN + 1] = {0};
    memcpy(longer, body.p, body.left);
    ln_rbuf more;
    ln_rbuf_init(&more, longer, body.left + 1);
    LN_CHECK_EQ(ln_proto_check_fields(LN_MSG_PUBLISH, &more), LN_EPROTOCOL);
    /* (the manager's messages are checked end to end by test_client_request.c) */
    LN_CHECK(ln_proto_to_client(LN_MSG_WELCOME) && ln_proto_to_client(LN_MSG_ERROR) &&
             ln_proto_to_client(LN_MSG_PORT_OK) && ln_proto_to_client(LN_MSG_OK) &&
             ln_proto_to_client(LN_MSG_TOPIC_INFO_OK));
    LN_CHECK(!ln_proto_to_client(LN_MSG_HELLO) && !ln_proto_to_client(LN_MSG_PUBLISH) &&
             !ln_proto_to_client(LN_MSG_SUBSCRIBE) && !ln_proto_to_client(LN_MSG_CLOSE_PORT) &&
             !ln_proto_to_client(LN_MSG_TOPIC_INFO) && !ln_proto_to_client(99));
}

int main(void)
{
    LN_TEST_RUN(test_integers);
    LN_TEST_RUN(test_strings_round_trip);
    LN_TEST_RUN(test_string_limits);
    LN_TEST_RUN(test_bad_utf8_rejected);
    LN_TEST_RUN(test_reading_past_end);
    LN_TEST_RUN(test_frame_encoding_and_round_trip);
    LN_TEST_RUN(test_hello_has_host_id);
    LN_TEST_RUN(test_every_truncation_rejected);
    LN_TEST_RUN(test_trailing_bytes_rejected);
    LN_TEST_RUN(test_header_bounds);
    LN_TEST_RUN(test_oversized_frame_not_encoded);
    LN_TEST_RUN(test_message_types);
    LN_TEST_RUN(test_text_fields);
    LN_TEST_RUN(test_check_fields);
    LN_TEST_EXIT();
}
