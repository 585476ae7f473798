// Key derivation, sealing and the replay window of forward_crypto.hpp, with libsodium's
// BLAKE2b (crypto_generichash), ChaCha20/Poly1305 and AES-256-GCM.
#include "forward_crypto.hpp"

#include <cstring>
#include <sodium.h>

namespace lnd::fwd::sec {

namespace {

void put64(uint8_t *p, uint64_t v) noexcept
{
    for (int i = 0; i < 8; ++i)
        p[i] = static_cast<uint8_t>(v >> (8 * i));
}

// The 96-bit AEAD nonce of a counter: its 8 bytes, then zeros.
void nonce_of(uint64_t counter, uint8_t nonce[12]) noexcept
{
    std::memset(nonce, 0, 12);
    put64(nonce, counter);
}

constexpr size_t kMaxAd = 128; // header and trailer, copied together for the AEAD suites

// The AEAD suites take header and trailer as one piece of additional data: joined in `all`
// (kMaxAd bytes) when there is a trailer, `ad` then points there; false if too long.
bool join_ad(const uint8_t *&ad, size_t &ad_size, const uint8_t *trailer, size_t trailer_size,
             uint8_t *all) noexcept
{
    if (trailer_size == 0)
        return true;
    if (ad_size + trailer_size > kMaxAd)
        return false;
    std::memcpy(all, ad, ad_size);
    std::memcpy(all + ad_size, trailer, trailer_size);
    ad = all;
    ad_size += trailer_size;
    return true;
}

} // namespace

const char *level_name(Level level) noexcept
{
    switch (level) {
    case Level::none:
        return "none";
    case Level::authenticate:
        return "authenticate";
    case Level::encrypt:
        return "encrypt";
    }
    return "?";
}

Suite suite_for(Level level) noexcept
{
    switch (level) {
    case Level::none:
        return Suite::none;
    case Level::authenticate:
        return Suite::poly1305;
    case Level::encrypt:
        return crypto_aead_aes256gcm_is_available() ? Suite::aes256gcm : Suite::chacha20poly1305;
    }
    return Suite::none;
}

bool suite_accepted(Level level, Suite suite) noexcept
{
    switch (level) {
    case Level::none:
        return suite == Suite::none;
    case Level::authenticate:
        return suite == Suite::poly1305;
    case Level::encrypt:
        return suite == Suite::chacha20poly1305 ||
               (suite == Suite::aes256gcm && crypto_aead_aes256gcm_is_available());
    }
    return false;
}

size_t tag_bytes(Suite suite) noexcept { return suite == Suite::none ? 0 : kTagBytes; }

void stream_key(const Key &daemon_key, uint64_t token, uint8_t transport, Key &out) noexcept
{
    // label || token || transport || direction (always "sender to receiver": a token names
    // one direction)
    static constexpr char kLabel[] = "ln forward stream key v1";
    uint8_t msg[sizeof kLabel + 8 + 2];
    std::memcpy(msg, kLabel, sizeof kLabel);
    put64(msg + sizeof kLabel, token);
    msg[sizeof kLabel + 8] = transport;
    msg[sizeof kLabel + 9] = 0;
    crypto_generichash(out.bytes, Key::kBytes, msg, sizeof msg, daemon_key.bytes, Key::kBytes);
}

void sub_key(const Key &stream, std::string_view label, const uint8_t *data, size_t size,
             Key &out) noexcept
{
    crypto_generichash_state st;
    crypto_generichash_init(&st, stream.bytes, Key::kBytes, Key::kBytes);
    crypto_generichash_update(&st, reinterpret_cast<const uint8_t *>(label.data()), label.size());
    uint8_t zero = 0;
    crypto_generichash_update(&st, &zero, 1);
    crypto_generichash_update(&st, data, size);
    crypto_generichash_final(&st, out.bytes, Key::kBytes);
    sodium_memzero(&st, sizeof st);
}

void handshake_tag(const Key &stream, const uint8_t *msg, size_t size,
                   uint8_t tag[kTagBytes]) noexcept
{
    static constexpr char kLabel[] = "ln forward handshake v1";
    crypto_generichash_state st;
    crypto_generichash_init(&st, stream.bytes, Key::kBytes, kTagBytes);
    crypto_generichash_update(&st, reinterpret_cast<const uint8_t *>(kLabel), sizeof kLabel);
    crypto_generichash_update(&st, msg, size);
    crypto_generichash_final(&st, tag, kTagBytes);
    sodium_memzero(&st, sizeof st); // keyed with the stream key
}

bool handshake_ok(const Key &stream, const uint8_t *msg, size_t size,
                  const uint8_t tag[kTagBytes]) noexcept
{
    uint8_t want[kTagBytes];
    handshake_tag(stream, msg, size, want);
    return crypto_verify_16(want, tag) == 0;
}

// ---- Box -------------------------------------------------------------------------------------

struct Box::AesState {
    crypto_aead_aes256gcm_state state;
};

Box::Box(const Key &key, Suite suite) noexcept : suite_(suite), key_(key)
{
    if (suite_ == Suite::aes256gcm) {
        aes_.reset(new (std::nothrow) AesState);
        if (aes_)
            crypto_aead_aes256gcm_beforenm(&aes_->state, key_.bytes);
    }
}

Box::~Box()
{
    if (aes_)
        sodium_memzero(&aes_->state, sizeof aes_->state);
}

void Box::mac(uint64_t counter, const uint8_t *ad, size_t ad_size, const uint8_t *payload,
              size_t size, const uint8_t *trailer, size_t trailer_size,
              uint8_t tag[kTagBytes]) noexcept
{
    uint8_t nonce[12];
    nonce_of(counter, nonce);
    uint8_t one_time[crypto_onetimeauth_KEYBYTES];
    crypto_stream_chacha20_ietf(one_time, sizeof one_time, nonce, key_.bytes);
    crypto_onetimeauth_state st;
    crypto_onetimeauth_init(&st, one_time);
    crypto_onetimeauth_update(&st, ad, ad_size);
    crypto_onetimeauth_update(&st, payload, size);
    if (trailer_size)
        crypto_onetimeauth_update(&st, trailer, trailer_size);
    uint8_t lengths[24];
    put64(lengths, ad_size);
    put64(lengths + 8, size);
    put64(lengths + 16, trailer_size);
    crypto_onetimeauth_update(&st, lengths, sizeof lengths);
    crypto_onetimeauth_final(&st, tag);
    sodium_memzero(one_time, sizeof one_time);
    sodium_memzero(&st, sizeof st);
}

void Box::seal(uint64_t counter, const uint8_t *ad, size_t ad_size, const uint8_t *in, size_t size,
               uint8_t *out, uint8_t tag[kTagBytes], const uint8_t *trailer,
               size_t trailer_size) noexcept
{
    if (suite_ == Suite::none)
        return;
    if (suite_ == Suite::poly1305) {
        mac(counter, ad, ad_size, in, size, trailer, trailer_size, tag);
        return;
    }
    uint8_t all[kMaxAd];
    if (!join_ad(ad, ad_size, trailer, trailer_size, all)) {
        std::memset(tag, 0, kTagBytes); // cannot happen with the wire's sizes: opens nowhere
        return;
    }
    uint8_t nothing = 0; // no payload (a torn frame): libsodium wants real pointers still
    if (size == 0)
        in = out = &nothing;
    uint8_t nonce[12];
    nonce_of(counter, nonce);
    unsigned long long tag_len = 0;
    if (suite_ == Suite::aes256gcm && aes_)
        crypto_aead_aes256gcm_encrypt_detached_afternm(out, tag, &tag_len, in, size, ad, ad_size,
                                                       nullptr, nonce, &aes_->state);
    else if (suite_ == Suite::chacha20poly1305)
        crypto_aead_chacha20poly1305_ietf_encrypt_detached(out, tag, &tag_len, in, size, ad,
                                                           ad_size, nullptr, nonce, key_.bytes);
    else
        std::memset(tag, 0, kTagBytes); // no AES state: opens nowhere
}

bool Box::open(uint64_t counter, const uint8_t *ad, size_t ad_size, const uint8_t *in, size_t size,
               uint8_t *out, const uint8_t tag[kTagBytes], const uint8_t *trailer,
               size_t trailer_size) noexcept
{
    if (suite_ == Suite::none)
        return true;
    if (suite_ == Suite::poly1305) {
        uint8_t want[kTagBytes];
        mac(counter, ad, ad_size, in, size, trailer, trailer_size, want);
        return crypto_verify_16(want, tag) == 0;
    }
    uint8_t all[kMaxAd];
    if (!join_ad(ad, ad_size, trailer, trailer_size, all))
        return false;
    uint8_t nothing = 0; // no payload (a torn frame): libsodium wants real pointers still
    if (size == 0)
        in = out = &nothing;
    uint8_t nonce[12];
    nonce_of(counter, nonce);
    if (suite_ == Suite::aes256gcm)
        return aes_ && crypto_aead_aes256gcm_decrypt_detached_afternm(
                           out, nullptr, in, size, tag, ad, ad_size, nonce, &aes_->state) == 0;
    return crypto_aead_chacha20poly1305_ietf_decrypt_detached(out, nullptr, in, size, tag, ad,
                                                              ad_size, nonce, key_.bytes) == 0;
}

// ---- ReplayWindow ----------------------------------------------------------------------------

ReplayWindow::Verdict ReplayWindow::check(uint64_t counter) const noexcept
{
    if (counter == 0 || counter > kMaxCounter)
        return Verdict::invalid;
    if (counter > top_)
        return Verdict::fresh;
    if (top_ - counter >= kBits)
        return Verdict::too_old;
    uint64_t bit = counter % kBits;
    return words_[bit / 64] >> (bit % 64) & 1 ? Verdict::duplicate : Verdict::fresh;
}

void ReplayWindow::accept(uint64_t counter) noexcept
{
    if (counter > top_) {
        // Clear the bits of the counters skipped over (all of them after a far jump).
        uint64_t gap = counter - top_;
        if (gap >= kBits) {
            std::memset(words_, 0, sizeof words_);
        } else {
            for (uint64_t c = top_ + 1; c < counter; ++c) {
                uint64_t bit = c % kBits;
                words_[bit / 64] &= ~(uint64_t{1} << (bit % 64));
            }
        }
        top_ = counter;
    }
    uint64_t bit = counter % kBits;
    words_[bit / 64] |= uint64_t{1} << (bit % 64);
}

void ReplayWindow::reset() noexcept
{
    top_ = 0;
    std::memset(words_, 0, sizeof words_);
}

} // namespace lnd::fwd::sec
