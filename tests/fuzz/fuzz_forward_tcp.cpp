// fuzz_forward_tcp.cpp — fuzz target: the forwarder's TCP stream receive code
// (forward_tcp_frame.cpp's TcpSession, which forward_tcp_recv.cpp runs on the socket's bytes):
// a sender's hello judged against the stream, then frame headers, payloads, trailers and tags,
// in the order and sizes the receive thread reads them; and a sender reading the receiver's
// reply, on the same bytes.  The stream's level is the hello's suite's, so the seeds cover
// none, authenticate and encrypt; the receiver's nonce is fixed so that seeds can be sealed.
// Every frame is judged twice, with its tag computed while the payload arrives in pieces and
// at once; the verdicts must agree.
#include <algorithm>
#include <cstdint>
#include <cstring>
#include <memory>
#include <vector>

#include "forward_crypto.hpp"
#include "forward_tcp_frame.hpp"
#include "forward_wire.hpp"

extern "C" {
#include "fuzz.h"
}

using namespace lnd::fwd;

namespace {

constexpr uint64_t kMessageSize = 64; // the RecvSpec of the stream
constexpr uint64_t kLayoutHash = 0x1122334455667788u;
constexpr uint64_t kToken = 0xfeed;
constexpr uint8_t kReceiverNonce[wire::kHandshakeNonce] = {7, 7, 7, 7, 7, 7, 7, 7,
                                                           7, 7, 7, 7, 7, 7, 7, 7};

const lnd::Key &stream_key()
{
    static const lnd::Key key = [] {
        lnd::Key daemon, out;
        std::memset(daemon.bytes, 0x24, lnd::Key::kBytes);
        sec::stream_key(daemon, kToken, 1, out);
        return out;
    }();
    return key;
}

sec::Level level_of(uint8_t suite)
{
    switch (static_cast<sec::Suite>(suite)) {
    case sec::Suite::none:
        return sec::Level::none;
    case sec::Suite::poly1305:
        return sec::Level::authenticate;
    default:
        return sec::Level::encrypt;
    }
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size >= wire::kReplySize) { // the sender's side: a reply
        wire::Reply reply;
        std::unique_ptr<sec::Box> box;
        uint8_t hello[wire::kHelloSize] = {};
        if (wire::decode_reply(data, reply))
            check_tcp_reply(hello, reply, data, stream_key(), sec::Suite::poly1305, box);
    }
    if (size < wire::kHelloSize)
        return 0;
    wire::Hello hello;
    if (!wire::decode_hello(data, hello) || hello.token != kToken)
        return 0;
    HelloRules rules{kMessageSize, kLayoutHash, level_of(hello.suite), &stream_key()};
    // `session` judges each frame as the receiver does, its tag computed while the payload
    // arrives in pieces (their size from the frame's seq); `whole` judges the same bytes at
    // once: the verdicts must agree.
    TcpSession session, whole;
    uint8_t reply[wire::kReplySize];
    if (session.accept(hello, data, rules, kReceiverNonce, reply) != wire::Reject::none ||
        whole.accept(hello, data, rules, kReceiverNonce, reply) != wire::Reject::none)
        return 0;
    data += wire::kHelloSize;
    size -= wire::kHelloSize;
    std::vector<uint8_t> payload(kMessageSize);
    uint8_t tail[wire::kFrameTrailerSize + sec::kTagBytes];
    const size_t tail_size = wire::kFrameTrailerSize + session.tag_size();
    while (size >= wire::kFrameHeaderSize) {
        wire::FrameHeader f;
        const uint8_t *head = data;
        if (session.header(head, f) != TcpSession::Frame::intact)
            break;
        data += wire::kFrameHeaderSize;
        size -= wire::kFrameHeaderSize;
        if (size < f.size + tail_size)
            break;
        std::memcpy(payload.data(), data, f.size);
        std::memcpy(tail, data + f.size, tail_size);
        data += f.size + tail_size;
        size -= f.size + tail_size;
        const size_t piece = 1 + f.seq % 97;
        session.begin(head);
        for (size_t at = 0; at < f.size; at += piece)
            session.part(payload.data() + at, std::min(piece, f.size - at));
        std::vector<uint8_t> copy = payload;
        TcpSession::Frame v =
            session.frame(head, payload.data(), tail, tail + wire::kFrameTrailerSize);
        if (whole.frame(head, copy.data(), tail, tail + wire::kFrameTrailerSize) != v)
            __builtin_trap(); // streaming judged differently
        if (v != TcpSession::Frame::intact && v != TcpSession::Frame::torn)
            break; // the connection ends
    }
    return 0;
}

extern "C" void ln_fuzz_seeds(ln_fuzz_emit *emit)
{
    for (sec::Level level : {sec::Level::none, sec::Level::authenticate, sec::Level::encrypt}) {
        const sec::Suite suite =
            level == sec::Level::encrypt ? sec::Suite::chacha20poly1305 : sec::suite_for(level);
        SendSpec spec;
        spec.token = kToken;
        spec.message_size = kMessageSize;
        spec.layout_hash = kLayoutHash;
        uint8_t nonce[wire::kHandshakeNonce] = {1, 2, 3};
        std::vector<uint8_t> buf(wire::kHelloSize);
        encode_tcp_hello(spec, stream_key(), suite, nonce, buf.data());
        // The receiver's reply, to derive the sender's key as a real sender would.
        wire::Hello hello;
        wire::decode_hello(buf.data(), hello);
        TcpSession session;
        uint8_t raw[wire::kReplySize];
        HelloRules rules{kMessageSize, kLayoutHash, level, &stream_key()};
        session.accept(hello, buf.data(), rules, kReceiverNonce, raw);
        wire::Reply reply;
        wire::decode_reply(raw, reply);
        std::unique_ptr<sec::Box> box;
        check_tcp_reply(buf.data(), reply, raw, stream_key(), suite, box);
        for (uint64_t seq = 1; seq <= 3; ++seq) {
            size_t at = buf.size();
            buf.resize(at + wire::kFrameHeaderSize + kMessageSize + wire::kFrameTrailerSize +
                       sec::tag_bytes(suite));
            uint8_t *p = buf.data() + at;
            wire::encode_frame_header(p, {seq, static_cast<int64_t>(seq) * 1000, kMessageSize});
            uint8_t *payload = p + wire::kFrameHeaderSize;
            std::memset(payload, static_cast<int>(seq), kMessageSize);
            uint8_t *trailer = payload + kMessageSize;
            wire::encode_frame_trailer(trailer, seq != 2); // the second one torn
            if (box)
                box->seal(seq, p, wire::kFrameHeaderSize, payload, kMessageSize, payload,
                          trailer + wire::kFrameTrailerSize, trailer, wire::kFrameTrailerSize);
        }
        const char *names[] = {"hello_three_frames", "authenticated_three_frames",
                               "encrypted_three_frames"};
        emit(names[static_cast<int>(level)], buf.data(), buf.size());
    }
    uint8_t reply[wire::kReplySize];
    wire::Reply r;
    r.kind = wire::Kind::reject;
    r.reason = wire::Reject::layout;
    r.token = kToken;
    wire::encode_reply(reply, r);
    emit("reply_reject", reply, sizeof reply);
}
