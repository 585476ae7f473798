// Key file checks and the HMAC computations of auth.hpp, with libsodium's
// crypto_auth_hmacsha256 and crypto_verify_32.
#include "auth.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fcntl.h>
#include <sodium.h>
#include <sys/stat.h>
#include <unistd.h>

#include "fd.hpp"

namespace lnd {

Key::Key(const Key &other) noexcept { std::memcpy(bytes, other.bytes, kBytes); }

Key &Key::operator=(const Key &other) noexcept
{
    std::memcpy(bytes, other.bytes, kBytes);
    return *this;
}

Key::~Key() { sodium_memzero(bytes, kBytes); }

bool crypto_init() noexcept { return sodium_init() >= 0; }

std::string key_id(const Key &key)
{
    static constexpr char kLabel[] = "ln key id";
    uint8_t hash[4];
    crypto_generichash(hash, sizeof hash, reinterpret_cast<const uint8_t *>(kLabel),
                       sizeof kLabel - 1, key.bytes, Key::kBytes);
    char text[9];
    std::snprintf(text, sizeof text, "%02x%02x%02x%02x", hash[0], hash[1], hash[2], hash[3]);
    return text;
}

namespace {

Outcome unusable(std::string text) { return outcome::error(proto::Err::os_error, std::move(text)); }

int hex_value(char c) noexcept
{
    if (c >= '0' && c <= '9')
        return c - '0';
    if (c >= 'a' && c <= 'f')
        return c - 'a' + 10;
    if (c >= 'A' && c <= 'F')
        return c - 'A' + 10;
    return -1;
}

} // namespace

Outcome load_key_file(const std::string &path, Key &key)
{
    UniqueFd fd(::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NOCTTY));
    if (!fd)
        return unusable("cannot open key file '" + path + "': " + std::strerror(errno));
    struct stat st;
    if (::fstat(fd.get(), &st) != 0)
        return unusable("cannot stat key file '" + path + "': " + std::strerror(errno));
    if (!S_ISREG(st.st_mode))
        return unusable("key file '" + path + "' is not a regular file");
    if (st.st_uid != ::geteuid())
        return unusable("key file '" + path + "' is owned by uid " + std::to_string(st.st_uid) +
                        ", not by this daemon's uid " + std::to_string(::geteuid()));
    if (st.st_mode & 077) {
        char mode[8];
        std::snprintf(mode, sizeof mode, "%04o", static_cast<unsigned>(st.st_mode & 07777));
        return unusable("key file '" + path + "' is accessible by group or others (mode " + mode +
                        "); it must be private: chmod 600 '" + path + "'");
    }
    char text[130];
    ssize_t n = ::read(fd.get(), text, sizeof text);
    if (n < 0)
        return unusable("cannot read key file '" + path + "': " + std::strerror(errno));
    size_t len = static_cast<size_t>(n);
    if (len > 0 && text[len - 1] == '\n')
        --len;
    bool valid = len == 2 * Key::kBytes;
    for (size_t i = 0; valid && i < Key::kBytes; ++i) {
        int hi = hex_value(text[2 * i]), lo = hex_value(text[2 * i + 1]);
        valid = hi >= 0 && lo >= 0;
        if (valid)
            key.bytes[i] = static_cast<uint8_t>(hi << 4 | lo);
    }
    sodium_memzero(text, sizeof text);
    if (!valid) {
        sodium_memzero(key.bytes, Key::kBytes);
        return unusable("key file '" + path +
                        "' holds no valid key: it must contain exactly 64 "
                        "hex digits (32 bytes), optionally followed by a newline");
    }
    return outcome::ok();
}

void random_bytes(void *out, size_t n) noexcept { randombytes_buf(out, n); }

void hmac(const uint8_t *key, size_t key_len, std::string_view label,
          std::initializer_list<std::string_view> parts, Tag out) noexcept
{
    crypto_auth_hmacsha256_state st;
    crypto_auth_hmacsha256_init(&st, key, key_len);
    crypto_auth_hmacsha256_update(&st, reinterpret_cast<const unsigned char *>(label.data()),
                                  label.size());
    const unsigned char zero = 0;
    crypto_auth_hmacsha256_update(&st, &zero, 1);
    for (std::string_view part : parts)
        crypto_auth_hmacsha256_update(&st, reinterpret_cast<const unsigned char *>(part.data()),
                                      part.size());
    crypto_auth_hmacsha256_final(&st, out);
    sodium_memzero(&st, sizeof st);
}

bool tag_equal(const Tag a, const Tag b) noexcept { return crypto_verify_32(a, b) == 0; }

void derive_session(const Key &key, const uint8_t *daemon_nonce, const uint8_t *client_nonce,
                    std::string_view instance, Session &out) noexcept
{
    std::string_view nd(reinterpret_cast<const char *>(daemon_nonce), 32);
    std::string_view nc(reinterpret_cast<const char *>(client_nonce), 32);
    hmac(key.bytes, Key::kBytes, "ln_daemon/1 client proof", {nd, nc, instance}, out.client_proof);
    hmac(key.bytes, Key::kBytes, "ln_daemon/1 daemon proof", {nd, nc, instance}, out.daemon_proof);
    hmac(key.bytes, Key::kBytes, "ln_daemon/1 to daemon", {nd, nc, instance}, out.to_daemon.bytes);
    hmac(key.bytes, Key::kBytes, "ln_daemon/1 to client", {nd, nc, instance}, out.to_client.bytes);
}

void frame_tag(const Key &key, uint64_t seq, const void *body, size_t size, Tag out) noexcept
{
    char seq_le[8];
    for (int i = 0; i < 8; ++i)
        seq_le[i] = static_cast<char>((seq >> (8 * i)) & 0xff);
    crypto_auth_hmacsha256_state st;
    crypto_auth_hmacsha256_init(&st, key.bytes, Key::kBytes);
    crypto_auth_hmacsha256_update(&st, reinterpret_cast<const unsigned char *>(seq_le), 8);
    crypto_auth_hmacsha256_update(&st, static_cast<const unsigned char *>(body), size);
    crypto_auth_hmacsha256_final(&st, out);
}

} // namespace lnd
