// Encoding and decoding of the forwarding wire format (forward_wire.hpp); byte by byte in
// little-endian order, so the result is the same on every host and alignment never matters.
#include "forward_wire.hpp"

#include <cstring>

namespace lnd::fwd::wire {

namespace {

void put16(uint8_t *p, uint16_t v) noexcept
{
    p[0] = static_cast<uint8_t>(v);
    p[1] = static_cast<uint8_t>(v >> 8);
}

void put32(uint8_t *p, uint32_t v) noexcept
{
    for (int i = 0; i < 4; ++i)
        p[i] = static_cast<uint8_t>(v >> (8 * i));
}

void put64(uint8_t *p, uint64_t v) noexcept
{
    for (int i = 0; i < 8; ++i)
        p[i] = static_cast<uint8_t>(v >> (8 * i));
}

uint16_t get16(const uint8_t *p) noexcept { return static_cast<uint16_t>(p[0] | p[1] << 8); }

uint32_t get32(const uint8_t *p) noexcept
{
    uint32_t v = 0;
    for (int i = 3; i >= 0; --i)
        v = v << 8 | p[i];
    return v;
}

uint64_t get64(const uint8_t *p) noexcept
{
    uint64_t v = 0;
    for (int i = 7; i >= 0; --i)
        v = v << 8 | p[i];
    return v;
}

// magic, version, kind, u16 field: the first 8 bytes of every message.
void put_prefix(uint8_t *p, Kind kind, uint16_t field) noexcept
{
    std::memcpy(p, kMagic, sizeof kMagic);
    p[4] = kVersion;
    p[5] = static_cast<uint8_t>(kind);
    put16(p + 6, field);
}

bool prefix_is(const uint8_t *p, Kind kind) noexcept
{
    return std::memcmp(p, kMagic, sizeof kMagic) == 0 && p[4] == kVersion &&
           p[5] == static_cast<uint8_t>(kind);
}

} // namespace

uint64_t fragment_count(uint64_t sample_size, uint16_t chunk_size) noexcept
{
    if (chunk_size == 0)
        return 0;
    uint64_t count = sample_size / chunk_size + (sample_size % chunk_size != 0);
    if (count == 0)
        count = 1; // an empty sample still travels as one (empty) fragment
    return count > UINT32_MAX ? 0 : count;
}

uint64_t fragment_length(uint64_t sample_size, uint16_t chunk_size, uint32_t index) noexcept
{
    uint64_t offset = static_cast<uint64_t>(index) * chunk_size;
    if (offset >= sample_size)
        return 0;
    uint64_t left = sample_size - offset;
    return left < chunk_size ? left : chunk_size;
}

// Layout (offsets in bytes):
//   0 magic "LNF1"   4 u8 version   5 u8 kind (0)   6 u16 chunk_size
//   8 u64 token     16 u64 seq     24 i64 timestamp_ns   32 u64 sample_size
//  40 u32 index     44 u32 count   48 u64 salt   56 u56 counter | u8 suite << 56
//  64 payload, then the 16-byte tag unless the suite is 0
void encode_fragment_header(uint8_t *out, const Fragment &f) noexcept
{
    put64(out + 48, f.salt);
    set_fragment_counter(out, f.suite, f.counter);
    put_prefix(out, Kind::fragment, f.chunk_size);
    put64(out + 8, f.token);
    put64(out + 16, f.seq);
    put64(out + 24, static_cast<uint64_t>(f.timestamp_ns));
    put64(out + 32, f.sample_size);
    put32(out + 40, f.index);
    put32(out + 44, f.count);
}

void set_fragment_index(uint8_t *header, uint32_t index) noexcept { put32(header + 40, index); }

void set_fragment_counter(uint8_t *header, uint8_t suite, uint64_t counter) noexcept
{
    put64(header + 56, (counter & 0x00ffffffffffffffu) | uint64_t{suite} << 56);
}

bool decode_fragment(const uint8_t *d, size_t size, Fragment &f) noexcept
{
    if (size < kFragmentHeaderSize || !prefix_is(d, Kind::fragment))
        return false;
    f.chunk_size = get16(d + 6);
    f.token = get64(d + 8);
    f.seq = get64(d + 16);
    f.timestamp_ns = static_cast<int64_t>(get64(d + 24));
    f.sample_size = get64(d + 32);
    f.index = get32(d + 40);
    f.count = get32(d + 44);
    f.salt = get64(d + 48);
    uint64_t word = get64(d + 56);
    f.suite = static_cast<uint8_t>(word >> 56);
    f.counter = word & 0x00ffffffffffffffu;
    f.data = d + kFragmentHeaderSize;
    f.length = size - kFragmentHeaderSize;
    f.tag = nullptr;
    if (f.suite != 0) {
        if (f.length < kFragmentTagSize)
            return false;
        f.length -= kFragmentTagSize;
        f.tag = f.data + f.length;
    }
    return true;
}

const char *check_fragment(const Fragment &f, uint64_t message_size) noexcept
{
    if (f.sample_size != message_size)
        return "sample size differs from the stream's message size";
    if (f.chunk_size == 0 || f.chunk_size > kMaxChunk)
        return "chunk size out of range";
    if (f.count != fragment_count(f.sample_size, f.chunk_size))
        return "fragment count does not match sample and chunk size";
    if (f.index >= f.count)
        return "fragment index out of range";
    if (f.length != fragment_length(f.sample_size, f.chunk_size, f.index))
        return "fragment length does not match its index";
    if (f.seq == 0)
        return "sequence number 0";
    return nullptr;
}

// Hello: prefix (kind 1, 0) | u64 token | u64 message_size | u64 layout_hash | u8 suite,
// 7 zero bytes | 16 nonce | 16 tag
void encode_hello(uint8_t *out, const Hello &h) noexcept
{
    put_prefix(out, Kind::hello, 0);
    put64(out + 8, h.token);
    put64(out + 16, h.message_size);
    put64(out + 24, h.layout_hash);
    put64(out + 32, h.suite);
    std::memcpy(out + 40, h.nonce, kHandshakeNonce);
    std::memcpy(out + 56, h.tag, kHandshakeTag);
}

bool decode_hello(const uint8_t *in, Hello &h) noexcept
{
    if (!prefix_is(in, Kind::hello) || get16(in + 6) != 0 || get64(in + 32) > 0xff)
        return false;
    h.token = get64(in + 8);
    h.message_size = get64(in + 16);
    h.layout_hash = get64(in + 24);
    h.suite = in[32];
    std::memcpy(h.nonce, in + 40, kHandshakeNonce);
    std::memcpy(h.tag, in + 56, kHandshakeTag);
    return true;
}

// Reply: prefix (kind 2 or 3, u16 reason) | u64 token | 16 nonce | 16 tag
void encode_reply(uint8_t *out, const Reply &r) noexcept
{
    put_prefix(out, r.kind, static_cast<uint16_t>(r.reason));
    put64(out + 8, r.token);
    std::memcpy(out + 16, r.nonce, kHandshakeNonce);
    std::memcpy(out + 32, r.tag, kHandshakeTag);
}

bool decode_reply(const uint8_t *in, Reply &r) noexcept
{
    if (prefix_is(in, Kind::accept) && get16(in + 6) == 0)
        r.kind = Kind::accept;
    else if (prefix_is(in, Kind::reject))
        r.kind = Kind::reject;
    else
        return false;
    r.reason = static_cast<Reject>(get16(in + 6));
    r.token = get64(in + 8);
    std::memcpy(r.nonce, in + 16, kHandshakeNonce);
    std::memcpy(r.tag, in + 32, kHandshakeTag);
    return true;
}

// Frame header: u64 seq | i64 timestamp_ns | u64 size, then size payload bytes.
void encode_frame_header(uint8_t *out, const FrameHeader &f) noexcept
{
    put64(out, f.seq);
    put64(out + 8, static_cast<uint64_t>(f.timestamp_ns));
    put64(out + 16, f.size);
}

FrameHeader decode_frame_header(const uint8_t *in) noexcept
{
    FrameHeader f;
    f.seq = get64(in);
    f.timestamp_ns = static_cast<int64_t>(get64(in + 8));
    f.size = get64(in + 16);
    return f;
}

// Frame trailer: "LNFE" | u32 state (0 intact, 1 torn).
constexpr uint8_t kTrailerMagic[4] = {'L', 'N', 'F', 'E'};

void encode_frame_trailer(uint8_t *out, bool intact) noexcept
{
    std::memcpy(out, kTrailerMagic, sizeof kTrailerMagic);
    put32(out + 4, intact ? 0 : 1);
}

Trailer decode_frame_trailer(const uint8_t *in) noexcept
{
    if (std::memcmp(in, kTrailerMagic, sizeof kTrailerMagic) != 0)
        return Trailer::invalid;
    switch (get32(in + 4)) {
    case 0:
        return Trailer::intact;
    case 1:
        return Trailer::torn;
    default:
        return Trailer::invalid;
    }
}

} // namespace lnd::fwd::wire
