/* fuzz_svc_wire.c — fuzz target: the service wire (svc_wire.c framing) as a hostile caller sends
 * it, written in pieces into a real provider connection (provider.c ln_svc_conn_readable: HELLO,
 * REQUEST decoding, the handler's answer); the provider must close it cleanly at the end. */
#include <assert.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#include "fuzz.h"
#include "svc_internal.h"

#define LAYOUT_HASH 0x5eed5eed5eed5eedull
#define SERVICE "planner"
#define REQUEST_SIG "double 8 7,double 8 1,uint32_t 4 1,[uint32_t 4 1,char* 1 1]* 12 1"
#define RESPONSE_SIG                                                                               \
    "uint32_t 4 1,[double 8 1,uint32_t 4 1,double 8 7,double 8 7,double 8 7]* "                    \
    "180 1,int32_t 4 1,uint32_t 4 1,char* 1 1"

static int handler(ln_client* clnt, ln_service_request* req, void* user_data)
{
    (void)clnt;
    (void)user_data;
    uint8_t request[76], response[4 + 12 + 4 + 12];
    ln_service_request_get_data(req, request);
    uint32_t waypoints;
    memcpy(&waypoints, request + 64, 4);
    if (waypoints % 2)
        return ln_service_request_respond_error(req, "odd");
    memset(response, 0, sizeof response);
    return ln_service_request_respond(req, response);
}

static void drain(int fd)
{
    char buf[4096];
    while (recv(fd, buf, sizeof buf, MSG_DONTWAIT) > 0)
        ;
}

/* What a caller's read_frame accepts: every frame header under a 4 KiB response limit. */
static void caller_headers(const uint8_t* data, size_t size)
{
    while (size >= LN_SVC_HEADER_SIZE) {
        uint32_t len;
        uint16_t type;
        int rc = ln_svc_parse_header(data, 4096, &len, &type);
        if (rc != LN_OK)
            return;
        assert(type >= LN_SVC_HELLO && type <= LN_SVC_SEALED && len <= 4096 + LN_SVC_OVERHEAD);
        if (size - LN_SVC_HEADER_SIZE < len)
            return;
        data += LN_SVC_HEADER_SIZE + len;
        size -= LN_SVC_HEADER_SIZE + len;
    }
}

int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    if (size < 1)
        return 0;
    size_t piece = (size_t)data[0] * 4 + 1; /* bytes per write: frames arrive in pieces */
    data++;
    size--;
    caller_headers(data, size);

    static ln_service_provider p; /* only the fields the connection code reads */
    static int ready;
    if (!ready) {
        snprintf(p.name, sizeof p.name, SERVICE);
        snprintf(p.md_name, sizeof p.md_name, "robot/plan_path");
        p.layout_hash = LAYOUT_HASH;
        if (ln_sig_parse(REQUEST_SIG, &p.req_sig) != LN_OK ||
            ln_sig_parse(RESPONSE_SIG, &p.resp_sig) != LN_OK)
            abort();
        p.request_size = ln_sig_size(p.req_sig);
        p.response_size = ln_sig_size(p.resp_sig);
        p.max_size = 1 << 16;
        p.handler = handler;
        atomic_store(&p.last_report_ns, INT64_MAX); /* never report calls to a manager */
        ready = 1;
    }
    int fds[2];
    if (socketpair(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK, 0, fds) != 0)
        abort();
    ln_svc_endpoint* ep = calloc(1, sizeof *ep);
    if (ep == NULL)
        abort();
    ep->kind = LN_SVC_EP_CONN;
    ep->fd = fds[0];
    ep->prov = &p;
    ln_wbuf_init(&ep->tx);
    ln_arena_init(&ep->arena, 0);

    int closed = 0;
    while (size > 0 && !closed) {
        size_t n = size < piece ? size : piece;
        ssize_t sent = send(fds[1], data, n, MSG_NOSIGNAL);
        if (sent <= 0)
            break; /* the provider closed its end */
        data += sent;
        size -= (size_t)sent;
        closed = ln_svc_conn_readable(ep) < 0;
        drain(fds[1]);
    }
    shutdown(fds[1], SHUT_WR);
    /* At the end of the stream the provider must give up within a few calls. */
    for (int i = 0; !closed; i++) {
        assert(i < 4);
        closed = ln_svc_conn_readable(ep) < 0;
        drain(fds[1]);
    }
    ln_svc_endpoint_free(ep);
    close(fds[1]);
    return 0;
}

/* ---- seeds: what a caller sends, built with the library's frame and signature encoders -- */

static void hello(ln_wbuf* b, const char* service, uint64_t hash)
{
    size_t s = ln_proto_frame_begin(b, LN_SVC_HELLO);
    ln_wbuf_u32(b, LN_SVC_MAGIC);
    ln_wbuf_u16(b, LN_SVC_VERSION);
    ln_wbuf_str(b, service);
    ln_wbuf_u64(b, hash);
    ln_svc_frame_end(b, s);
}

static void request(ln_wbuf* b, uint32_t call_id, uint32_t waypoints)
{
    ln_sig* sig;
    if (ln_sig_parse(REQUEST_SIG, &sig) != LN_OK)
        return;
    uint8_t msg[76], wp[3][12];
    memset(msg, 0, sizeof msg);
    const char* name = "via";
    for (int i = 0; i < 3; i++) {
        uint32_t len = 3;
        memcpy(wp[i], &len, 4);
        memcpy(wp[i] + 4, &name, sizeof name);
    }
    void* ptr = wp;
    memcpy(msg + 64, &waypoints, 4);
    memcpy(msg + 68, &ptr, sizeof ptr);
    size_t s = ln_proto_frame_begin(b, LN_SVC_REQUEST);
    ln_wbuf_u32(b, call_id);
    ln_sig_encode(sig, msg, b, 1 << 16);
    ln_svc_frame_end(b, s);
    ln_sig_free(sig);
}

static void emit_buf(ln_fuzz_emit* emit, const char* name, uint8_t piece, ln_wbuf* b)
{
    ln_wbuf out;
    ln_wbuf_init(&out);
    ln_wbuf_bytes(&out, &piece, 1);
    ln_wbuf_bytes(&out, b->data, b->len);
    emit(name, out.data, out.len);
    ln_wbuf_free(&out);
    ln_wbuf_free(b);
}

void ln_fuzz_seeds(ln_fuzz_emit* emit)
{
    ln_wbuf b;
    ln_wbuf_init(&b);
    hello(&b, SERVICE, LAYOUT_HASH);
    request(&b, 1, 2);
    request(&b, 2, 1);
    emit_buf(emit, "hello_two_requests", 255, &b);

    ln_wbuf_init(&b);
    hello(&b, SERVICE, LAYOUT_HASH);
    request(&b, 7, 0);
    emit_buf(emit, "hello_request_in_pieces", 2, &b);

    ln_wbuf_init(&b);
    hello(&b, "other", LAYOUT_HASH);
    emit_buf(emit, "hello_wrong_service", 255, &b);

    ln_wbuf_init(&b);
    hello(&b, SERVICE, 1);
    emit_buf(emit, "hello_wrong_layout", 255, &b);

    ln_wbuf_init(&b);
    ln_svc_put_error(&b, 0, LN_EPROTOCOL, "a caller never sends this");
    emit_buf(emit, "error_frame", 255, &b);
}
