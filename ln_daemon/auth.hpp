// The shared key and what is computed with it (docs/daemon.md, "Authentication"): loading
// and checking the key file, the handshake proofs, the per-direction session keys and the
// tag of every frame after the handshake.  All HMAC-SHA256 from libsodium.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "outcome.hpp"

namespace lnd {

struct Key {
    static constexpr size_t kBytes = 32;
    uint8_t bytes[kBytes] = {};
    Key() = default;
    Key(const Key &other) noexcept;
    Key &operator=(const Key &other) noexcept;
    ~Key(); // wipes the bytes
};

using Tag = uint8_t[32];

// Must run once before anything else here (sodium_init); false if libsodium is unusable.
bool crypto_init() noexcept;

// Reads a key file: a regular file owned by the daemon's uid, no permission bits for
// group or others, holding 64 hex digits (optionally followed by a newline).
// Refused with error os_error and a sentence.
Outcome load_key_file(const std::string &path, Key &key);

void random_bytes(void *out, size_t n) noexcept;

// A short name of a key for logs (8 hex digits of a BLAKE2b hash of it, not the key): hosts
// that log the same id hold the same key.
std::string key_id(const Key &key);

// HMAC-SHA256(key, label || 0 || each part in turn).
void hmac(const uint8_t *key, size_t key_len, std::string_view label,
          std::initializer_list<std::string_view> parts, Tag out) noexcept;

// Constant-time comparison of two tags.
bool tag_equal(const Tag a, const Tag b) noexcept;

// What the handshake derives from the key, both nonces and the instance name.
struct Session {
    Tag client_proof; // the client sends it, the daemon checks it
    Tag daemon_proof; // the daemon sends it, the client checks it
    Key to_daemon;    // tags frames client -> daemon
    Key to_client;    // tags frames daemon -> client
};
void derive_session(const Key &key, const uint8_t *daemon_nonce, const uint8_t *client_nonce,
                    std::string_view instance, Session &out) noexcept;

// Tag of one frame: HMAC-SHA256(direction key, sequence number u64le || frame body).
void frame_tag(const Key &key, uint64_t seq, const void *body, size_t size, Tag out) noexcept;

} // namespace lnd
