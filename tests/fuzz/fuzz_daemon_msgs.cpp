// fuzz_daemon_msgs.cpp — fuzz target: ln_daemon's command codec (the Reader of wire_io.hpp,
// the generated daemon_wire.hpp behind messages.hpp, net_messages.cpp, logger_messages.cpp,
// pull_messages.cpp; spec.cpp) on a stream of manager frames, each decoded by its type's
// decoder; a decoded SPAWN goes through check_spawn, and a decoded request of the generated
// codec is encoded back and must decode again.  (Frame HMAC tags are left out.)
#include <cassert>
#include <cstdint>
#include <cstring>
#include <string>

#include "logger_messages.hpp"
#include "messages.hpp"
#include "net_messages.hpp"
#include "protocol.hpp"
#include "pull_messages.hpp"
#include "spec.hpp"

extern "C" {
#include "fuzz.h"
}

using namespace lnd;
using proto::Msg;

namespace {

uint32_t le32(const uint8_t *p)
{
    return uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24;
}

// A decoded request encoded again, as the Python client does, and decoded once more.
template <typename Request, typename Encode, typename Decode>
void round_trip(const Request &req, Encode encode, Decode decode_again)
{
    proto::Writer w;
    encode(w, req);
    proto::Reader again(w.buffer().data(), w.buffer().size());
    Request copy;
    bool ok = decode_again(again, copy);
    assert(ok);
    (void)ok;
}

void encode_logger_topic(proto::Writer &w, const LoggerTopicRequest &req) { wire::encode(w, req); }

// One request body, decoded as Server::handle_hello / handle_request, NetCommands and
// Loggers do.
void decode(uint8_t type, proto::Reader &r)
{
    switch (static_cast<Msg>(type)) {
    case Msg::client_hello: {
        wire::ClientHello hello;
        if (wire::decode(r, hello))
            valid_name(hello.instance);
        break;
    }
    case Msg::spawn: {
        SpawnRequest req;
        if (decode_spawn(r, req)) {
            env_default(req.env, "LN_HOST_ID", "fuzzhost");
            LaunchSpec launch;
            ProcessConfig config;
            Outcome o = check_spawn(req, launch, config);
            assert(!o.failed() || !o.text.empty());
            (void)o;
            round_trip(
                req, [](proto::Writer &w, const SpawnRequest &q) { wire::encode(w, q); },
                decode_spawn);
        }
        break;
    }
    case Msg::stop:
    case Msg::forget: {
        wire::Stop req;
        if (wire::decode(r, req))
            valid_name(req.name);
        break;
    }
    case Msg::output: {
        wire::Output req;
        auto encode = [](proto::Writer &w, const wire::Output &q) { wire::encode(w, q); };
        auto decode_again = [](proto::Reader &again, wire::Output &q) {
            return wire::decode(again, q);
        };
        if (wire::decode(r, req))
            round_trip(req, encode, decode_again);
        break;
    }
    case Msg::signal: {
        wire::Signal req;
        if (wire::decode(r, req))
            valid_name(req.name);
        break;
    }
    case Msg::ring_create: {
        RingCreateRequest req;
        if (decode_ring_create(r, req))
            assert(req.name.size() <= proto::kMaxName);
        break;
    }
    case Msg::ring_retire: {
        RingRetireRequest req;
        decode_ring_retire(r, req);
        break;
    }
    case Msg::ring_reader: {
        RingReaderRequest req;
        decode_ring_reader(r, req);
        break;
    }
    case Msg::ring_counts: {
        RingCountsRequest req;
        decode_ring_counts(r, req);
        break;
    }
    case Msg::ring_remove:
    case Msg::ring_seq: {
        std::string name;
        decode_ring_name(r, name);
        break;
    }
    case Msg::stream_send: {
        fwd::SendSpec spec;
        decode_stream_send(r, spec);
        break;
    }
    case Msg::stream_recv: {
        fwd::RecvSpec spec;
        decode_stream_recv(r, spec);
        break;
    }
    case Msg::stream_remove: {
        uint64_t token;
        decode_stream_token(r, token);
        break;
    }
    case Msg::logger_topic: {
        LoggerTopicRequest req;
        if (decode_logger_topic(r, req)) {
            assert(req.logger.size() <= proto::kMaxName && req.ring.size() <= proto::kMaxName);
            round_trip(req, encode_logger_topic, decode_logger_topic);
        }
        break;
    }
    case Msg::logger_remove: {
        LoggerRemoveRequest req;
        decode_logger_remove(r, req);
        break;
    }
    case Msg::logger_enable: {
        LoggerEnableRequest req;
        if (decode_logger_enable(r, req))
            round_trip(
                req, [](proto::Writer &w, const LoggerEnableRequest &q) { wire::encode(w, q); },
                decode_logger_enable);
        break;
    }
    case Msg::logger_fetch: {
        LoggerFetchRequest req;
        decode_logger_fetch(r, req);
        break;
    }
    case Msg::logger_status: {
        std::string logger;
        decode_logger_status(r, logger);
        break;
    }
    case Msg::pull_topic: {
        PullTopicRequest req;
        if (decode_pull_topic(r, req)) {
            assert(req.name.size() <= kMaxPullName && req.key.size() <= kMaxPullKey);
            round_trip(req, encode_pull_topic, decode_pull_topic);
        }
        break;
    }
    case Msg::pull_remove:
    case Msg::pull_status: {
        std::string topic;
        decode_pull_topic_name(r, topic);
        break;
    }
    default:
        r.done();
        break;
    }
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    // Frames: u32 length, then type u8, request id u32 and the body (Server::parse_frames).
    while (size >= proto::kLengthBytes) {
        uint32_t len = le32(data);
        if (len < proto::kHeaderBytes || len > size - proto::kLengthBytes)
            break;
        const uint8_t *body = data + proto::kLengthBytes;
        proto::Reader r(body + proto::kHeaderBytes, len - proto::kHeaderBytes);
        try {
            decode(body[0], r);
        } catch (const std::bad_alloc &) {
            // the daemon drops the connection (Server::on_readable); nothing else may throw
        }
        data += proto::kLengthBytes + len;
        size -= proto::kLengthBytes + len;
    }
    return 0;
}

// ---- seeds: frames built with the daemon's own Writer ----------------------------------------

namespace {

void frame(std::string &out, Msg type, proto::Writer &body)
{
    proto::Writer w;
    w.u32(static_cast<uint32_t>(proto::kHeaderBytes + body.buffer().size()));
    w.u8(static_cast<uint8_t>(type));
    w.u32(7);
    out += w.buffer() + body.buffer();
}

} // namespace

extern "C" void ln_fuzz_seeds(ln_fuzz_emit *emit)
{
    std::string out;
    {
        proto::Writer w;
        w.raw(proto::kMagic, sizeof proto::kMagic);
        w.u16(proto::kVersion);
        uint8_t nonce[proto::kNonceBytes] = {1, 2, 3};
        w.raw(nonce, sizeof nonce);
        w.str("testinstance");
        uint8_t proof[32] = {9};
        w.raw(proof, sizeof proof);
        frame(out, Msg::client_hello, w);
    }
    emit("client_hello", out.data(), out.size());

    out.clear();
    {
        proto::Writer w;
        w.str("camera");
        w.u8(kSpawnPty);
        w.u32(2);
        w.str("/bin/sleep");
        w.str("10");
        w.u32(1);
        w.str("LN_MANAGER=127.0.0.1:54411");
        w.str("/tmp");
        w.u32(1);
        w.str("RLIMIT_NOFILE");
        w.i64(1024);
        w.i64(-1);
        w.str("SCHED_FIFO");
        w.i32(10);
        w.u32(2);
        w.u32(0);
        w.u32(1);
        w.u32(1000);
        w.str("/tmp/camera.log");
        w.u64(1 << 20);
        w.u32(3);
        w.i32(15);
        w.f64(2.5);
        frame(out, Msg::spawn, w);
    }
    {
        proto::Writer w;
        w.str("camera");
        w.i32(2);
        w.u8(1);
        frame(out, Msg::signal, w);
    }
    emit("spawn_signal", out.data(), out.size());

    out.clear();
    {
        proto::Writer w;
        w.str("/ln.testinstance.1.1");
        w.str("/arm/state");
        w.str("robot/joint_state");
        w.u64(0x1122334455667788u);
        w.u64(96);
        w.u32(8);
        w.u8(1);
        frame(out, Msg::ring_create, w);
    }
    {
        proto::Writer w;
        w.str("/ln.testinstance.1.1");
        w.str("/ln.testinstance.1.2");
        w.f64(1.0);
        frame(out, Msg::ring_retire, w);
    }
    {
        proto::Writer w;
        w.str("/ln.testinstance.1.2");
        w.u32(3);
        w.i32(1234);
        w.u32(4);
        w.u8(1);
        frame(out, Msg::ring_reader, w);
    }
    {
        proto::Writer w;
        w.str("/ln.testinstance.1.2");
        w.u32(1);
        w.u32(2);
        frame(out, Msg::ring_counts, w);
    }
    emit("rings", out.data(), out.size());

    out.clear();
    {
        proto::Writer w;
        w.u64(0xfeedu);
        w.str("/ln.i.1.1");
        w.u64(42);
        w.u64(96);
        w.u8(1);
        w.str("10.0.0.2");
        w.u16(54377);
        frame(out, Msg::stream_send, w);
    }
    {
        proto::Writer w;
        w.u64(0xfeedu);
        w.str("/ln.i.1.1");
        w.u64(42);
        w.u64(96);
        w.u8(0);
        frame(out, Msg::stream_recv, w);
    }
    {
        proto::Writer w;
        w.u64(0xfeedu);
        frame(out, Msg::stream_remove, w);
    }
    emit("streams", out.data(), out.size());

    out.clear();
    {
        LoggerTopicRequest req;
        req.logger = "blackbox";
        req.topic = "/arm/state";
        req.ring = "/ln.testinstance.1.1";
        req.md_name = "robot/joint_state";
        req.layout_hash = 0x1122334455667788u;
        req.message_size = 96;
        req.depth = 1000;
        req.divisor = 10;
        req.span_s = 2.5;
        proto::Writer w;
        encode_logger_topic(w, req);
        frame(out, Msg::logger_topic, w);
    }
    {
        proto::Writer w;
        w.str("blackbox");
        w.u8(1);
        w.u8(1);
        frame(out, Msg::logger_enable, w);
    }
    {
        proto::Writer w;
        w.str("blackbox");
        w.str("/arm/state");
        w.u64(41);
        w.u32(1 << 20);
        frame(out, Msg::logger_fetch, w);
    }
    {
        proto::Writer w;
        w.str("");
        frame(out, Msg::logger_status, w);
    }
    {
        proto::Writer w;
        w.str("blackbox");
        w.str("");
        frame(out, Msg::logger_remove, w);
    }
    emit("loggers", out.data(), out.size());

    out.clear();
    {
        PullTopicRequest req;
        req.topic = "arm.state";
        req.ring = "/ln.testinstance.1.1";
        req.md_name = "robot/joint_state";
        req.layout_hash = 0x1122334455667788u;
        req.message_size = 96;
        req.address = "0.0.0.0";
        req.port = 6363;
        req.name = "/ln/testinstance/arm.state";
        req.history = 64;
        req.freshness_ms = 1000;
        req.signature = 4;
        req.key = "secret";
        proto::Writer w;
        encode_pull_topic(w, req);
        frame(out, Msg::pull_topic, w);
    }
    {
        proto::Writer w;
        w.str("");
        frame(out, Msg::pull_status, w);
    }
    {
        proto::Writer w;
        w.str("arm.state");
        frame(out, Msg::pull_remove, w);
    }
    emit("pulls", out.data(), out.size());
}
