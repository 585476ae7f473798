// fuzz_forward_tcp.cpp — fuzz target: the forwarder's TCP stream wire (forward_wire.cpp):
// a receiver reading a sender's hello and then frame headers, payloads and trailers, as
// forward_tcp_recv.cpp does, and a sender reading the receiver's reply, on the same bytes.
#include <cstdint>
#include <cstring>

#include "forward_wire.hpp"

extern "C" {
#include "fuzz.h"
}

using namespace lnd::fwd;

namespace {

constexpr uint64_t kMessageSize = 64; // the RecvSpec of the stream
constexpr uint64_t kLayoutHash = 0x1122334455667788u;
constexpr uint64_t kToken = 0xfeed;

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size >= wire::kReplySize) {
        wire::Reply reply;
        wire::decode_reply(data, reply);
    }
    if (size < wire::kHelloSize)
        return 0;
    wire::Hello hello;
    if (!wire::decode_hello(data, hello) || hello.token != kToken ||
        hello.message_size != kMessageSize || hello.layout_hash != kLayoutHash)
        return 0;
    data += wire::kHelloSize;
    size -= wire::kHelloSize;
    uint8_t payload[kMessageSize];
    uint64_t last_seq = 0;
    while (size >= wire::kFrameHeaderSize) {
        wire::FrameHeader f = wire::decode_frame_header(data);
        data += wire::kFrameHeaderSize;
        size -= wire::kFrameHeaderSize;
        if (f.size != kMessageSize || size < f.size + wire::kFrameTrailerSize)
            break;
        std::memcpy(payload, data, f.size);
        data += f.size;
        size -= f.size;
        wire::Trailer t = wire::decode_frame_trailer(data);
        data += wire::kFrameTrailerSize;
        size -= wire::kFrameTrailerSize;
        if (t == wire::Trailer::invalid)
            break;
        if (t == wire::Trailer::intact)
            last_seq = f.seq;
    }
    (void)last_seq;
    return 0;
}

extern "C" void ln_fuzz_seeds(ln_fuzz_emit *emit)
{
    uint8_t buf[wire::kHelloSize +
                3 * (wire::kFrameHeaderSize + kMessageSize + wire::kFrameTrailerSize)];
    size_t n = 0;
    wire::Hello h;
    h.token = kToken;
    h.message_size = kMessageSize;
    h.layout_hash = kLayoutHash;
    wire::encode_hello(buf, h);
    n += wire::kHelloSize;
    for (uint64_t seq = 1; seq <= 3; ++seq) {
        wire::FrameHeader f;
        f.seq = seq;
        f.timestamp_ns = static_cast<int64_t>(seq) * 1000;
        f.size = kMessageSize;
        wire::encode_frame_header(buf + n, f);
        n += wire::kFrameHeaderSize;
        std::memset(buf + n, static_cast<int>(seq), kMessageSize);
        n += kMessageSize;
        wire::encode_frame_trailer(buf + n, seq != 2); // the second one torn
        n += wire::kFrameTrailerSize;
    }
    emit("hello_three_frames", buf, n);
    uint8_t reply[wire::kReplySize];
    wire::Reply r;
    r.kind = wire::Kind::reject;
    r.reason = wire::Reject::layout;
    r.token = kToken;
    wire::encode_reply(reply, r);
    emit("reply_reject", reply, sizeof reply);
}
