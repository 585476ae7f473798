/* fuzz_proto.c — fuzz target: the client <-> manager frame codec (libln/src/proto.c) on a
 * stream a hostile manager could send: header, frame and field checks of every frame, then the
 * client's field readers for what passes (client_conn.c, port.c, service.c, svc_key.c). */
#include <assert.h>
#include <string.h>

#include "fuzz.h"
#include "proto.h"

/* Reads a checked body the way the client does; every field must be there. */
static void read_fields(uint16_t type, ln_rbuf r)
{
    char text[LN_PROTO_MAX_STR + 1], small[256];
    switch (type) {
    case LN_MSG_WELCOME: /* client_conn.c handshake() */
        ln_rbuf_u16(&r);
        ln_rbuf_u32(&r);
        ln_rbuf_str(&r, text, sizeof text);
        ln_rbuf_str(&r, text, sizeof text);
        break;
    case LN_MSG_ERROR: /* take_error() */
        ln_rbuf_u32(&r);
        ln_rbuf_i32(&r);
        ln_rbuf_str(&r, text, sizeof text);
        break;
    case LN_MSG_PORT_OK: /* port.c: port id, segment, reader index */
        ln_rbuf_u32(&r);
        ln_rbuf_u32(&r);
        ln_rbuf_str(&r, small, sizeof small);
        ln_rbuf_u32(&r);
        /* a segment name longer than the port's buffer is refused, not truncated */
        assert(r.failed || strlen(small) < sizeof small);
        return;
    case LN_MSG_SERVICE_INFO: /* service.c: id, provider, host, unix path, tcp host, port, sig */
        ln_rbuf_u32(&r);
        for (int i = 0; i < 4; i++)
            ln_rbuf_str(&r, text, sizeof text);
        ln_rbuf_u16(&r);
        ln_rbuf_str(&r, text, sizeof text);
        break;
    case LN_MSG_TOPIC_INFO_OK:
        ln_rbuf_u32(&r);
        ln_rbuf_str(&r, text, sizeof text);
        ln_rbuf_u64(&r);
        ln_rbuf_u32(&r);
        ln_rbuf_u32(&r);
        ln_rbuf_u32(&r);
        break;
    case LN_MSG_CONTROL_RESULT: { /* control.c: id, the answer's JSON text */
        size_t n;
        ln_rbuf_u32(&r);
        const char* json = ln_rbuf_text(&r, &n);
        assert(r.failed || (json != NULL && memchr(json, '\0', n) == NULL));
        break;
    }
    case LN_MSG_CHALLENGE: { /* client_conn.c answer_challenge() */
        ln_msg_challenge ch;
        ln_msg_challenge_read(&r, &ch);
        break;
    }
    case LN_MSG_AUTH_OK: {
        ln_msg_auth_ok ok;
        ln_msg_auth_ok_read(&r, &ok);
        break;
    }
    case LN_MSG_SERVICE_KEY_INFO: { /* svc_key.c take_info(), after the request id */
        ln_msg_service_key_info info;
        ln_rbuf_u32(&r);
        ln_msg_service_key_info_read_after_id(&r, &info);
        break;
    }
    default: /* OK */
        ln_rbuf_u32(&r);
        break;
    }
    /* ln_proto_check_fields promised exactly these fields */
    assert(ln_rbuf_end(&r) == LN_OK);
}

int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    while (size >= LN_PROTO_HEADER_SIZE) {
        uint32_t body_len;
        uint16_t type;
        if (ln_proto_parse_header(data, &body_len, &type) != LN_OK)
            return 0; /* the client closes the connection */
        size_t frame = LN_PROTO_HEADER_SIZE + (size_t)body_len;
        ln_rbuf body;
        uint16_t type2;
        int rc = ln_proto_decode_frame(data, frame < size ? frame : size, &type2, &body);
        if (rc != LN_OK) {
            assert(frame > size); /* only a truncated frame may fail after a good header */
            return 0;
        }
        assert(type2 == type && body.left == body_len);
        /* every type, as the manager side would check it too */
        for (uint16_t t = 0; t <= LN_MSG_CONTROL_RESULT + 1; t++)
            ln_proto_check_fields(t, &body);
        if (ln_proto_to_client(type)) {
            ln_rbuf peek = body;
            int welcome_other = type == LN_MSG_WELCOME && ln_rbuf_u16(&peek) != LN_PROTO_VERSION;
            if (!welcome_other && ln_proto_check_fields(type, &body) == LN_OK)
                read_fields(type, body);
        }
        data += frame;
        size -= frame;
    }
    return 0;
}

/* ---- seeds: frames as the manager sends them ------------------------------------------- */

static void emit_frames(ln_fuzz_emit* emit, const char* name, ln_wbuf* b)
{
    emit(name, b->data, b->len);
    ln_wbuf_free(b);
}

void ln_fuzz_seeds(ln_fuzz_emit* emit)
{
    ln_wbuf b;
    ln_wbuf_init(&b);
    size_t s = ln_proto_frame_begin(&b, LN_MSG_WELCOME);
    ln_wbuf_u16(&b, LN_PROTO_VERSION);
    ln_wbuf_u32(&b, 42);
    ln_wbuf_str(&b, "cam-2");
    ln_wbuf_str(&b, "testinstance");
    ln_proto_frame_end(&b, s);
    s = ln_proto_frame_begin(&b, LN_MSG_OK);
    ln_wbuf_u32(&b, 1);
    ln_proto_frame_end(&b, s);
    emit_frames(emit, "welcome_ok", &b);

    ln_wbuf_init(&b);
    s = ln_proto_frame_begin(&b, LN_MSG_ERROR);
    ln_wbuf_u32(&b, 0);
    ln_wbuf_i32(&b, LN_EVERSION);
    ln_wbuf_str(&b, "protocol 2 is not spoken here \xc3\xa4");
    ln_proto_frame_end(&b, s);
    emit_frames(emit, "error", &b);

    ln_wbuf_init(&b);
    s = ln_proto_frame_begin(&b, LN_MSG_PORT_OK);
    ln_wbuf_u32(&b, 1);
    ln_wbuf_u32(&b, 7);
    ln_wbuf_str(&b, "/ln-testinstance-joints-1");
    ln_wbuf_u32(&b, 3);
    ln_proto_frame_end(&b, s);
    s = ln_proto_frame_begin(&b, LN_MSG_TOPIC_INFO_OK);
    ln_wbuf_u32(&b, 2);
    ln_wbuf_str(&b, "robot/joint_state");
    ln_wbuf_u64(&b, 0x1234567890abcdefull);
    ln_wbuf_u32(&b, 176);
    ln_wbuf_u32(&b, 1);
    ln_wbuf_u32(&b, 2);
    ln_proto_frame_end(&b, s);
    emit_frames(emit, "port_ok_topic_info", &b);

    ln_wbuf_init(&b);
    s = ln_proto_frame_begin(&b, LN_MSG_SERVICE_INFO);
    ln_wbuf_u32(&b, 5);
    ln_wbuf_str(&b, "planner");
    ln_wbuf_str(&b, "host-1");
    ln_wbuf_str(&b, "/tmp/ln-0/testinstance/svc-planner");
    ln_wbuf_str(&b, "127.0.0.1");
    ln_wbuf_u16(&b, 40000);
    ln_wbuf_str(&b, "double 8 7|uint32_t 4 1,char* 1 1");
    ln_proto_frame_end(&b, s);
    emit_frames(emit, "service_info", &b);

    ln_wbuf_init(&b);
    s = ln_proto_frame_begin(&b, LN_MSG_CONTROL_RESULT);
    ln_wbuf_u32(&b, 6);
    ln_wbuf_text(&b, "{\"ok\": false, \"error\": \"no logger 'x'\", \"code\": \"ENOTFOUND\"}");
    ln_proto_frame_end(&b, s);
    emit_frames(emit, "control_result", &b);
}
