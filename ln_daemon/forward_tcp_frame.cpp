// The TCP handshake and frame checks of forward_tcp_frame.hpp.  Both sides' fresh nonces go
// into the connection key, so a recorded connection played to a receiver again fails at its
// first frame, and frames carry no counter: the n-th frame of a connection is opened with n.
#include "forward_tcp_frame.hpp"

#include <cstring>
#include <sodium.h>

namespace lnd::fwd {

namespace {

Key connection_key(const Key &stream_key, const uint8_t *sender_nonce,
                   const uint8_t *receiver_nonce)
{
    uint8_t both[2 * wire::kHandshakeNonce];
    std::memcpy(both, sender_nonce, wire::kHandshakeNonce);
    std::memcpy(both + wire::kHandshakeNonce, receiver_nonce, wire::kHandshakeNonce);
    Key k;
    sec::sub_key(stream_key, "tcp connection", both, sizeof both, k);
    return k;
}

// The reply's tag covers its first kReplyTagged bytes and the hello's nonce: an accept
// recorded for another connection does not fit.
void reply_tag(const Key &stream_key, const uint8_t *reply_raw, const uint8_t *hello_nonce,
               uint8_t tag[sec::kTagBytes])
{
    uint8_t covered[wire::kReplyTagged + wire::kHandshakeNonce];
    std::memcpy(covered, reply_raw, wire::kReplyTagged);
    std::memcpy(covered + wire::kReplyTagged, hello_nonce, wire::kHandshakeNonce);
    sec::handshake_tag(stream_key, covered, sizeof covered, tag);
}

} // namespace

wire::Reject TcpSession::accept(const wire::Hello &hello, const uint8_t *hello_raw,
                                const HelloRules &rules, const uint8_t nonce[wire::kHandshakeNonce],
                                uint8_t reply[wire::kReplySize])
{
    const auto suite = static_cast<sec::Suite>(hello.suite);
    if (!sec::suite_accepted(rules.security, suite))
        return wire::Reject::security;
    if (suite != sec::Suite::none &&
        !sec::handshake_ok(*rules.stream_key, hello_raw, wire::kHelloTagged, hello.tag))
        return wire::Reject::key;
    if (hello.message_size != rules.message_size || hello.layout_hash != rules.layout_hash)
        return wire::Reject::layout;
    message_size_ = rules.message_size;
    counter_ = 0;
    wire::Reply r;
    r.kind = wire::Kind::accept;
    r.token = hello.token;
    if (suite != sec::Suite::none)
        std::memcpy(r.nonce, nonce, wire::kHandshakeNonce);
    wire::encode_reply(reply, r);
    box_.reset();
    if (suite != sec::Suite::none) {
        reply_tag(*rules.stream_key, reply, hello.nonce, r.tag);
        wire::encode_reply(reply, r);
        box_ = std::make_unique<sec::Box>(connection_key(*rules.stream_key, hello.nonce, nonce),
                                          suite);
    }
    return wire::Reject::none;
}

TcpSession::Frame TcpSession::header(const uint8_t head[wire::kFrameHeaderSize],
                                     wire::FrameHeader &f) const noexcept
{
    f = wire::decode_frame_header(head);
    return f.size == message_size_ ? Frame::intact : Frame::bad_size;
}

void TcpSession::begin(const uint8_t head[wire::kFrameHeaderSize]) noexcept
{
    fed_ = 0;
    streaming_ =
        box_ && box_->streams() && box_->mac_begin(counter_ + 1, head, wire::kFrameHeaderSize);
}

void TcpSession::part(const uint8_t *data, size_t size) noexcept
{
    if (streaming_) {
        streaming_ = box_->mac_update(data, size);
        fed_ += size;
    }
}

TcpSession::Frame TcpSession::frame(const uint8_t head[wire::kFrameHeaderSize], uint8_t *payload,
                                    const uint8_t tail[wire::kFrameTrailerSize],
                                    const uint8_t *tag) noexcept
{
    ++counter_;
    const wire::Trailer trailer = wire::decode_frame_trailer(tail);
    const size_t covered = tagged_payload(trailer != wire::Trailer::torn, message_size_);
    const bool streamed = streaming_ && fed_ == covered && covered == message_size_;
    streaming_ = false;
    if (box_ && streamed &&
        !box_->mac_check(wire::kFrameHeaderSize, covered, tail, wire::kFrameTrailerSize, tag))
        return Frame::rejected;
    if (box_ && !streamed &&
        !box_->open(counter_, head, wire::kFrameHeaderSize, payload, covered, payload, tag, tail,
                    wire::kFrameTrailerSize))
        return Frame::rejected;
    switch (trailer) {
    case wire::Trailer::intact:
        return Frame::intact;
    case wire::Trailer::torn:
        return Frame::torn;
    default:
        return Frame::bad_trailer;
    }
}

void encode_tcp_hello(const SendSpec &spec, const Key &stream_key, sec::Suite suite,
                      const uint8_t nonce[wire::kHandshakeNonce], uint8_t out[wire::kHelloSize])
{
    wire::Hello h;
    h.token = spec.token;
    h.message_size = spec.message_size;
    h.layout_hash = spec.layout_hash;
    h.suite = static_cast<uint8_t>(suite);
    if (suite != sec::Suite::none)
        std::memcpy(h.nonce, nonce, wire::kHandshakeNonce);
    wire::encode_hello(out, h);
    if (suite != sec::Suite::none) {
        sec::handshake_tag(stream_key, out, wire::kHelloTagged, h.tag);
        wire::encode_hello(out, h);
    }
}

bool check_tcp_reply(const uint8_t hello_raw[wire::kHelloSize], const wire::Reply &reply,
                     const uint8_t reply_raw[wire::kReplySize], const Key &stream_key,
                     sec::Suite suite, std::unique_ptr<sec::Box> &box)
{
    box.reset();
    if (suite == sec::Suite::none)
        return true;
    const uint8_t *hello_nonce = hello_raw + 40; // Hello::nonce (forward_wire.cpp)
    uint8_t want[sec::kTagBytes];
    reply_tag(stream_key, reply_raw, hello_nonce, want);
    if (crypto_verify_16(want, reply.tag) != 0)
        return false;
    box = std::make_unique<sec::Box>(connection_key(stream_key, hello_nonce, reply.nonce), suite);
    return true;
}

} // namespace lnd::fwd
