// The protection of forwarded data (docs/security.md, "Host-to-host data"): the per-stream
// keys derived from the daemon key, the tag (and, for `encrypt`, the cipher) of every UDP
// datagram and TCP frame, and the UDP replay window.  libsodium and OpenSSL's libcrypto; no
// sockets, so the unit tests and the fuzz targets use it as the data path does.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string_view>

#include "auth.hpp"

namespace lnd::fwd::sec {

// What the instance asks for (the `security` key of the .lnc instance section).
enum class Level : uint8_t { none = 0, authenticate = 1, encrypt = 2 };

// How a datagram or frame is protected; travels in every UDP header and TCP hello.
enum class Suite : uint8_t {
    none = 0,             // no tag
    poly1305 = 1,         // authenticate: Poly1305 tag over header and payload, one-time key
                          // from ChaCha20 under the stream key and the counter
    chacha20poly1305 = 2, // encrypt: ChaCha20-Poly1305 (IETF), header as additional data
    aes256gcm = 3,        // encrypt: AES-256-GCM where the CPU has AES-NI and PCLMUL
};

constexpr size_t kTagBytes = 16;
constexpr size_t kNonceBytes = 16;                        // each side's fresh TCP nonce
constexpr uint64_t kMaxCounter = (uint64_t{1} << 56) - 1; // UDP counters are 56 bits on the wire

const char *level_name(Level level) noexcept;
// The suite this host sends with for `level` (encrypt: AES-256-GCM when available).
Suite suite_for(Level level) noexcept;
// Whether a receiver of `level` takes data protected with `suite` (and can open it here).
bool suite_accepted(Level level, Suite suite) noexcept;
size_t tag_bytes(Suite suite) noexcept; // 0 for none

// The key of one stream and direction: BLAKE2b-256 keyed with the daemon key over a label,
// the token, the transport and which end sends.  A token names one stream from one sender
// to one receiver, so both daemons derive the same key without sending anything secret.
void stream_key(const Key &daemon_key, uint64_t token, uint8_t transport, Key &out) noexcept;
// A key for one sender incarnation (UDP: its salt) or one connection (TCP: both nonces):
// BLAKE2b-256 keyed with the stream key over `label` and `data`.
void sub_key(const Key &stream, std::string_view label, const uint8_t *data, size_t size,
             Key &out) noexcept;
// A 16-byte tag of a handshake message (TCP hello and accept) under the stream key.
void handshake_tag(const Key &stream, const uint8_t *msg, size_t size,
                   uint8_t tag[kTagBytes]) noexcept;
bool handshake_ok(const Key &stream, const uint8_t *msg, size_t size,
                  const uint8_t tag[kTagBytes]) noexcept;

// Seals and opens the datagrams or frames of one key (one salt or one connection).  The
// counter is the nonce: the caller never uses one twice with the same Box.
class Box {
public:
    Box(const Key &key, Suite suite) noexcept;
    ~Box();
    Box(const Box &) = delete;
    Box &operator=(const Box &) = delete;

    Suite suite() const noexcept { return suite_; }
    // Tags `ad` (header, not encrypted) and `size` payload bytes at `in`; with an encrypting
    // suite the payload is encrypted into `out` (may be `in`), else `out` is not written.
    // `trailer` (optional, not encrypted) is authenticated after the payload.
    void seal(uint64_t counter, const uint8_t *ad, size_t ad_size, const uint8_t *in, size_t size,
              uint8_t *out, uint8_t tag[kTagBytes], const uint8_t *trailer = nullptr,
              size_t trailer_size = 0) noexcept;
    // The reverse: false (and `out` unspecified) if the tag does not match.
    bool open(uint64_t counter, const uint8_t *ad, size_t ad_size, const uint8_t *in, size_t size,
              uint8_t *out, const uint8_t tag[kTagBytes], const uint8_t *trailer = nullptr,
              size_t trailer_size = 0) noexcept;

    // poly1305 only (streams()): the tag of a frame whose payload is fed in pieces as it
    // arrives: mac_begin with the counter and header, mac_update with each piece in order,
    // then mac_check with the sizes, the trailer and the tag received (false: not authentic,
    // or a failure).  Gives what open() gives for the same bytes.
    bool streams() const noexcept { return suite_ == Suite::poly1305; }
    bool mac_begin(uint64_t counter, const uint8_t *ad, size_t ad_size) noexcept;
    bool mac_update(const uint8_t *data, size_t size) noexcept;
    bool mac_check(size_t ad_size, size_t size, const uint8_t *trailer, size_t trailer_size,
                   const uint8_t tag[kTagBytes]) noexcept;

private:
    bool mac_end(size_t ad_size, size_t size, const uint8_t *trailer, size_t trailer_size,
                 uint8_t tag[kTagBytes]) noexcept;
    // poly1305: the tag of header, payload, trailer and their lengths; false on failure.
    bool mac(uint64_t counter, const uint8_t *ad, size_t ad_size, const uint8_t *payload,
             size_t size, const uint8_t *trailer, size_t trailer_size,
             uint8_t tag[kTagBytes]) noexcept;
    // The AEAD suites: seals (tag out) or opens (tag checked); false on failure.
    bool aead(bool encrypt, uint64_t counter, const uint8_t *ad, size_t ad_size, const uint8_t *in,
              size_t size, uint8_t *out, uint8_t tag[kTagBytes]) noexcept;

    const Suite suite_;
    Key key_;
    struct Engine;
    std::unique_ptr<Engine> engine_; // OpenSSL's MAC or keyed cipher context
};

// Which counters of one salt were seen: a sliding bitmap of kBits counters below the highest
// authentic one (RFC 6479's ring of words).  check() before authenticating, accept() after.
class ReplayWindow {
public:
    static constexpr uint64_t kBits = 4096;
    enum class Verdict { fresh, duplicate, too_old, invalid };
    Verdict check(uint64_t counter) const noexcept;
    void accept(uint64_t counter) noexcept;
    void reset() noexcept;
    uint64_t top() const noexcept { return top_; }

private:
    static constexpr uint64_t kWords = kBits / 64;
    uint64_t top_ = 0; // highest accepted counter, 0: none yet
    uint64_t words_[kWords] = {};
};

} // namespace lnd::fwd::sec
