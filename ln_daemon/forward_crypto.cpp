// Key derivation, sealing and the replay window of forward_crypto.hpp: libsodium's BLAKE2b
// (crypto_generichash) for the keys, OpenSSL's libcrypto for Poly1305 and the AEAD ciphers.
#include "forward_crypto.hpp"

#include <cstring>
#include <openssl/evp.h>
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
        return suite == Suite::chacha20poly1305 || suite == Suite::aes256gcm;
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
//
// The bulk work (Poly1305 over the payload, the AEAD ciphers) runs in OpenSSL's libcrypto,
// whose AVX2/AVX-512 code takes a third of libsodium's time for a 1 MiB sample (Poly1305 66
// against 207 µs here); the results are the same bytes (RFC 8439 and GCM), so daemons of
// either build forward to each other.  A Box is used by one thread at a time.

namespace {

// OpenSSL's Poly1305, fetched once for the process.
EVP_MAC *poly1305_mac() noexcept
{
    static EVP_MAC *mac = EVP_MAC_fetch(nullptr, "POLY1305", nullptr);
    return mac;
}

// Feeds `size` bytes to an AEAD context (OpenSSL takes int lengths); false on failure.
bool aead_update(EVP_CIPHER_CTX *ctx, bool encrypt, uint8_t *out, const uint8_t *in,
                 size_t size) noexcept
{
    constexpr size_t kPiece = size_t{1} << 30;
    while (size > 0) {
        int n = static_cast<int>(size < kPiece ? size : kPiece), done = 0;
        if ((encrypt ? EVP_EncryptUpdate(ctx, out, &done, in, n)
                     : EVP_DecryptUpdate(ctx, out, &done, in, n)) != 1)
            return false;
        if (out)
            out += n;
        in += n;
        size -= static_cast<size_t>(n);
    }
    return true;
}

} // namespace

struct Box::Engine {
    EVP_MAC_CTX *mac = nullptr;       // poly1305
    EVP_CIPHER_CTX *cipher = nullptr; // the AEAD suites, keyed once
    ~Engine()
    {
        EVP_MAC_CTX_free(mac);
        EVP_CIPHER_CTX_free(cipher); // cleans the expanded key
    }
};

Box::Box(const Key &key, Suite suite) noexcept : suite_(suite), key_(key)
{
    engine_.reset(new (std::nothrow) Engine);
    if (!engine_)
        return;
    if (suite_ == Suite::poly1305) {
        if (EVP_MAC *mac = poly1305_mac())
            engine_->mac = EVP_MAC_CTX_new(mac);
        return;
    }
    const EVP_CIPHER *kind = suite_ == Suite::aes256gcm          ? EVP_aes_256_gcm()
                             : suite_ == Suite::chacha20poly1305 ? EVP_chacha20_poly1305()
                                                                 : nullptr;
    if (!kind)
        return;
    engine_->cipher = EVP_CIPHER_CTX_new();
    // The key now, the nonce per datagram or frame (12 bytes is both ciphers' default).
    if (engine_->cipher &&
        EVP_CipherInit_ex(engine_->cipher, kind, nullptr, key_.bytes, nullptr, 1) != 1) {
        EVP_CIPHER_CTX_free(engine_->cipher);
        engine_->cipher = nullptr;
    }
}

Box::~Box() { sodium_memzero(key_.bytes, Key::kBytes); }

bool Box::mac_begin(uint64_t counter, const uint8_t *ad, size_t ad_size) noexcept
{
    if (!engine_ || !engine_->mac)
        return false;
    uint8_t nonce[12];
    nonce_of(counter, nonce);
    uint8_t one_time[crypto_onetimeauth_KEYBYTES];
    crypto_stream_chacha20_ietf(one_time, sizeof one_time, nonce, key_.bytes);
    bool ok = EVP_MAC_init(engine_->mac, one_time, sizeof one_time, nullptr) == 1 &&
              EVP_MAC_update(engine_->mac, ad, ad_size) == 1;
    sodium_memzero(one_time, sizeof one_time);
    return ok;
}

bool Box::mac_update(const uint8_t *data, size_t size) noexcept
{
    return engine_ && engine_->mac && (size == 0 || EVP_MAC_update(engine_->mac, data, size) == 1);
}

bool Box::mac_end(size_t ad_size, size_t size, const uint8_t *trailer, size_t trailer_size,
                  uint8_t tag[kTagBytes]) noexcept
{
    if (!engine_ || !engine_->mac)
        return false;
    uint8_t lengths[24];
    put64(lengths, ad_size);
    put64(lengths + 8, size);
    put64(lengths + 16, trailer_size);
    size_t out = 0;
    return (trailer_size == 0 || EVP_MAC_update(engine_->mac, trailer, trailer_size) == 1) &&
           EVP_MAC_update(engine_->mac, lengths, sizeof lengths) == 1 &&
           EVP_MAC_final(engine_->mac, tag, &out, kTagBytes) == 1 && out == kTagBytes;
}

bool Box::mac_check(size_t ad_size, size_t size, const uint8_t *trailer, size_t trailer_size,
                    const uint8_t tag[kTagBytes]) noexcept
{
    uint8_t want[kTagBytes];
    return mac_end(ad_size, size, trailer, trailer_size, want) && crypto_verify_16(want, tag) == 0;
}

bool Box::mac(uint64_t counter, const uint8_t *ad, size_t ad_size, const uint8_t *payload,
              size_t size, const uint8_t *trailer, size_t trailer_size,
              uint8_t tag[kTagBytes]) noexcept
{
    return mac_begin(counter, ad, ad_size) && mac_update(payload, size) &&
           mac_end(ad_size, size, trailer, trailer_size, tag);
}

bool Box::aead(bool encrypt, uint64_t counter, const uint8_t *ad, size_t ad_size, const uint8_t *in,
               size_t size, uint8_t *out, uint8_t tag[kTagBytes]) noexcept
{
    EVP_CIPHER_CTX *ctx = engine_ ? engine_->cipher : nullptr;
    if (!ctx)
        return false;
    uint8_t nonce[12];
    nonce_of(counter, nonce);
    int done = 0;
    if (EVP_CipherInit_ex(ctx, nullptr, nullptr, nullptr, nonce, encrypt ? 1 : 0) != 1 ||
        (ad_size > 0 && !aead_update(ctx, encrypt, nullptr, ad, ad_size)) ||
        (size > 0 && !aead_update(ctx, encrypt, out, in, size)))
        return false;
    if (encrypt)
        return EVP_EncryptFinal_ex(ctx, out, &done) == 1 &&
               EVP_CIPHER_CTX_ctrl(ctx, EVP_CTRL_AEAD_GET_TAG, kTagBytes, tag) == 1;
    return EVP_CIPHER_CTX_ctrl(ctx, EVP_CTRL_AEAD_SET_TAG, kTagBytes, tag) == 1 &&
           EVP_DecryptFinal_ex(ctx, out, &done) == 1;
}

void Box::seal(uint64_t counter, const uint8_t *ad, size_t ad_size, const uint8_t *in, size_t size,
               uint8_t *out, uint8_t tag[kTagBytes], const uint8_t *trailer,
               size_t trailer_size) noexcept
{
    if (suite_ == Suite::none)
        return;
    bool ok;
    if (suite_ == Suite::poly1305) {
        ok = mac(counter, ad, ad_size, in, size, trailer, trailer_size, tag);
    } else {
        uint8_t all[kMaxAd];
        ok = join_ad(ad, ad_size, trailer, trailer_size, all) &&
             aead(true, counter, ad, ad_size, in, size, out, tag);
    }
    if (!ok)
        std::memset(tag, 0, kTagBytes); // cannot happen with the wire's sizes: opens nowhere
}

bool Box::open(uint64_t counter, const uint8_t *ad, size_t ad_size, const uint8_t *in, size_t size,
               uint8_t *out, const uint8_t tag[kTagBytes], const uint8_t *trailer,
               size_t trailer_size) noexcept
{
    if (suite_ == Suite::none)
        return true;
    if (suite_ == Suite::poly1305)
        return mac_begin(counter, ad, ad_size) && mac_update(in, size) &&
               mac_check(ad_size, size, trailer, trailer_size, tag);
    uint8_t all[kMaxAd];
    uint8_t expected[kTagBytes];
    std::memcpy(expected, tag, kTagBytes); // OpenSSL takes a writable tag
    return join_ad(ad, ad_size, trailer, trailer_size, all) &&
           aead(false, counter, ad, ad_size, in, size, out, expected);
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
