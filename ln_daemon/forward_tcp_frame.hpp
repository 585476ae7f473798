// The receive side's judgement of a TCP stream's bytes, without sockets: whether a hello is
// taken (and with which connection key), and whether each frame is intact, torn, malformed
// or not authentic.  forward_tcp_recv.cpp reads the socket and asks these; the fuzz target
// tests/fuzz/fuzz_forward_tcp.cpp feeds them arbitrary bytes.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>

#include "forward.hpp"
#include "forward_crypto.hpp"
#include "forward_wire.hpp"

namespace lnd::fwd {

// Payload bytes a frame's tag covers: all of them, but none of a torn frame (its payload
// may have changed while it was sent from the ring slot; the tag covers header and
// trailer, so the torn verdict is authentic too).
constexpr size_t tagged_payload(bool intact, size_t message_size) noexcept
{
    return intact ? message_size : 0;
}

// What the receiver knows of the stream a hello names.
struct HelloRules {
    uint64_t message_size = 0;
    uint64_t layout_hash = 0;
    sec::Level security = sec::Level::authenticate;
    const Key *stream_key = nullptr; // sec::stream_key of the stream
};

// The frames of one accepted connection: their counter and key.
class TcpSession {
public:
    // Judges `hello` (decoded) against the stream: Reject::none if it is taken, then `reply`
    // holds the accept message to send (with a fresh nonce and its tag) and the session its
    // key; else the reason to refuse it.  `nonce` is the receiver's fresh nonce.
    wire::Reject accept(const wire::Hello &hello, const uint8_t *hello_raw, const HelloRules &rules,
                        const uint8_t nonce[wire::kHandshakeNonce],
                        uint8_t reply[wire::kReplySize]);

    enum class Frame { intact, torn, bad_size, bad_trailer, rejected };
    // The frame header's verdict before the payload is read: bad_size if it does not carry
    // a sample of the stream's size (else intact).
    Frame header(const uint8_t head[wire::kFrameHeaderSize], wire::FrameHeader &f) const noexcept;
    // After payload, trailer and tag (tag_size() bytes) were read: whether it is authentic
    // (the payload decrypted in place) and intact.  A frame that is not authentic ends the
    // connection, as does a bad trailer.
    Frame frame(const uint8_t head[wire::kFrameHeaderSize], uint8_t *payload,
                const uint8_t tail[wire::kFrameTrailerSize], const uint8_t *tag) noexcept;
    // Streaming (authenticate): the tag of the next frame's payload is computed while it
    // arrives: begin() after its header, part() with each piece in order; frame() then
    // only finishes it (if the payload was fed whole and the frame is intact; otherwise it
    // computes the tag over what it is given, as without).
    void begin(const uint8_t head[wire::kFrameHeaderSize]) noexcept;
    void part(const uint8_t *data, size_t size) noexcept;
    size_t tag_size() const noexcept { return box_ ? sec::kTagBytes : 0; }
    uint64_t message_size() const noexcept { return message_size_; }

private:
    uint64_t message_size_ = 0;
    uint64_t counter_ = 0; // of the last frame
    std::unique_ptr<sec::Box> box_;
    bool streaming_ = false; // begin() was called for the next frame and every part() took
    uint64_t fed_ = 0;       // payload bytes given to part() since begin()
};

// The sender's half: the hello to send, and whether the reply accepts it (then the key of
// the connection's frames).  `why` says what is wrong otherwise.
void encode_tcp_hello(const SendSpec &spec, const Key &stream_key, sec::Suite suite,
                      const uint8_t nonce[wire::kHandshakeNonce], uint8_t out[wire::kHelloSize]);
bool check_tcp_reply(const uint8_t hello_raw[wire::kHelloSize], const wire::Reply &reply,
                     const uint8_t reply_raw[wire::kReplySize], const Key &stream_key,
                     sec::Suite suite, std::unique_ptr<sec::Box> &box);

} // namespace lnd::fwd
