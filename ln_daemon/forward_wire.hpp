// The forwarding wire format (docs/network.md, "Wire format"): the header of every UDP
// datagram, and the hello, reply, frame header and frame trailer of a TCP stream.  Pure
// encode/decode, all little-endian, no sockets, so the unit tests can feed it anything.  The
// tags that protect them are forward_crypto.hpp's.
#pragma once

#include <cstddef>
#include <cstdint>

namespace lnd::fwd::wire {

constexpr uint8_t kMagic[4] = {'L', 'N', 'F', '1'};
constexpr uint8_t kVersion = 3; // 2: TCP frames end in a trailer; 3: security suite and tags

enum class Kind : uint8_t {
    fragment = 0, // UDP: one piece of a sample
    hello = 1,    // TCP, sender -> receiver: which stream this connection carries
    accept = 2,   // TCP, receiver -> sender: go ahead
    reject = 3,   // TCP, receiver -> sender: refused (reason), then the receiver closes
};

// Why a receiver refused a TCP stream.
enum class Reject : uint16_t {
    none = 0,
    unknown_stream = 1, // no RecvSpec with this token and transport tcp
    layout = 2,         // message size or layout hash differ from the RecvSpec's
    busy = 3,           // too many connections
    security = 4,       // the hello's suite does not fit the receiver's security level
    key = 5,            // the hello's tag is wrong: the sender has another key
};

// ---- UDP -------------------------------------------------------------------------------------

constexpr size_t kFragmentHeaderSize = 64;
constexpr size_t kFragmentTagSize = 16; // after the payload, unless the suite is 0 (none)
constexpr size_t kMaxDatagram = 65507;  // largest UDP payload over IPv4
constexpr size_t kMaxChunk = kMaxDatagram - kFragmentHeaderSize - kFragmentTagSize;

struct Fragment {
    uint64_t token = 0;
    uint64_t seq = 0;
    int64_t timestamp_ns = 0;
    uint64_t sample_size = 0;      // bytes of the whole sample
    uint32_t index = 0;            // of this fragment, 0 .. count-1
    uint32_t count = 0;            // fragments of the sample
    uint16_t chunk_size = 0;       // payload bytes of every fragment but the last (the sender's)
    uint8_t suite = 0;             // sec::Suite: how it is protected
    uint64_t salt = 0;             // the sender's incarnation (0 with suite none)
    uint64_t counter = 0;          // datagram number under this salt, 56 bits (0 with none)
    const uint8_t *data = nullptr; // this fragment's payload (cipher text when encrypted)
    size_t length = 0;
    const uint8_t *tag = nullptr; // kFragmentTagSize bytes, nullptr with suite none
};

// Fragments a sample of `sample_size` bytes is cut into with chunks of `chunk_size` (> 0);
// 0 if that is more than a u32 holds.
uint64_t fragment_count(uint64_t sample_size, uint16_t chunk_size) noexcept;
// Payload bytes of fragment `index` (< count).
uint64_t fragment_length(uint64_t sample_size, uint16_t chunk_size, uint32_t index) noexcept;

// Writes the kFragmentHeaderSize bytes of `f`'s header (data/length are not used).
void encode_fragment_header(uint8_t *out, const Fragment &f) noexcept;
// Only the fragment index and the counter differ between the fragments of one sample.
void set_fragment_index(uint8_t *header, uint32_t index) noexcept;
void set_fragment_counter(uint8_t *header, uint8_t suite, uint64_t counter) noexcept;
// Parses the header of a datagram of `size` bytes: false if it is not one of ours at all
// (too short, magic, version, kind, too short for its tag).  The geometry is checked separately,
// against the stream, by check_fragment.
bool decode_fragment(const uint8_t *datagram, size_t size, Fragment &f) noexcept;
// nullptr if the fragment is consistent with itself and with a stream of `message_size`,
// else what is wrong with it.
const char *check_fragment(const Fragment &f, uint64_t message_size) noexcept;

// ---- TCP -------------------------------------------------------------------------------------

constexpr size_t kHelloSize = 72;
constexpr size_t kHelloTagged = 56; // the hello's bytes its tag covers
constexpr size_t kReplySize = 48;
constexpr size_t kReplyTagged = 32; // the reply's bytes its tag covers (and the hello's nonce)
constexpr size_t kHandshakeNonce = 16;
constexpr size_t kHandshakeTag = 16;
constexpr size_t kFrameHeaderSize = 24;
constexpr size_t kFrameTrailerSize = 8;

struct Hello {
    uint64_t token = 0;
    uint64_t message_size = 0;
    uint64_t layout_hash = 0;
    uint8_t suite = 0;                   // sec::Suite of the frames that follow
    uint8_t nonce[kHandshakeNonce] = {}; // the sender's, fresh for the connection
    uint8_t tag[kHandshakeTag] = {};     // over the first kHelloTagged bytes
};

struct Reply {
    Kind kind = Kind::accept; // accept or reject
    Reject reason = Reject::none;
    uint64_t token = 0;
    uint8_t nonce[kHandshakeNonce] = {}; // the receiver's, fresh for the connection
    uint8_t tag[kHandshakeTag] = {};     // over kReplyTagged bytes and the hello's nonce
};

struct FrameHeader {
    uint64_t seq = 0;
    int64_t timestamp_ns = 0;
    uint64_t size = 0;
};

// Encoding writes the tag fields as they are: compute them over the encoded bytes first,
// then encode again (or patch the last kHandshakeTag bytes).
void encode_hello(uint8_t *out, const Hello &h) noexcept;
bool decode_hello(const uint8_t *in, Hello &h) noexcept; // false: not a hello of this version
void encode_reply(uint8_t *out, const Reply &r) noexcept;
bool decode_reply(const uint8_t *in, Reply &r) noexcept;
void encode_frame_header(uint8_t *out, const FrameHeader &f) noexcept;
FrameHeader decode_frame_header(const uint8_t *in) noexcept;

// What follows a frame's payload: whether the payload stayed intact while it was sent (a
// sender sends straight from the ring, where the publisher may overwrite a sample it falls
// a whole ring behind on).  A torn frame is dropped by the receiver.
enum class Trailer { intact, torn, invalid };
void encode_frame_trailer(uint8_t *out, bool intact) noexcept;
Trailer decode_frame_trailer(const uint8_t *in) noexcept; // invalid: not a trailer

} // namespace lnd::fwd::wire
