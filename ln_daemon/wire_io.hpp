// The little-endian Writer and Reader every daemon message is built and parsed with
// (docs/daemon.md, "Frames"); the generated codec (daemon_wire.hpp) is written on them.
// A Reader never reads past its buffer: the first short read marks it failed, and the
// caller checks ok() once at the end.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>

namespace lnd::proto {

// Longest string a Reader takes unless told otherwise: the frame limit (daemon.schema's
// MAX_FRAME, checked against it in protocol.hpp).
constexpr size_t kMaxString = 4u << 20;

class Writer {
public:
    void u8(uint8_t v) { buf_.push_back(static_cast<char>(v)); }
    void u16(uint16_t v) { le(v, 2); }
    void u32(uint32_t v) { le(v, 4); }
    void u64(uint64_t v) { le(v, 8); }
    void i32(int32_t v) { le(static_cast<uint32_t>(v), 4); }
    void i64(int64_t v) { le(static_cast<uint64_t>(v), 8); }
    void f64(double v)
    {
        uint64_t bits;
        std::memcpy(&bits, &v, sizeof bits);
        le(bits, 8);
    }
    void raw(const void *p, size_t n) { buf_.append(static_cast<const char *>(p), n); }
    void str(std::string_view s)
    {
        u32(static_cast<uint32_t>(s.size()));
        buf_.append(s.data(), s.size());
    }
    std::string &buffer() { return buf_; }

private:
    void le(uint64_t v, int n)
    {
        for (int i = 0; i < n; ++i)
            buf_.push_back(static_cast<char>((v >> (8 * i)) & 0xff));
    }
    std::string buf_;
};

class Reader {
public:
    Reader(const void *data, size_t size) noexcept
        : p_(static_cast<const uint8_t *>(data)), left_(size)
    {}
    uint8_t u8() noexcept { return static_cast<uint8_t>(le(1)); }
    uint16_t u16() noexcept { return static_cast<uint16_t>(le(2)); }
    uint32_t u32() noexcept { return static_cast<uint32_t>(le(4)); }
    uint64_t u64() noexcept { return le(8); }
    int32_t i32() noexcept { return static_cast<int32_t>(static_cast<uint32_t>(le(4))); }
    int64_t i64() noexcept { return static_cast<int64_t>(le(8)); }
    double f64() noexcept
    {
        uint64_t bits = le(8);
        double v;
        std::memcpy(&v, &bits, sizeof v);
        return v;
    }
    // Copies n raw bytes into out (zeros on failure).
    void raw(void *out, size_t n) noexcept
    {
        if (!take(n)) {
            std::memset(out, 0, n);
            return;
        }
        std::memcpy(out, p_ - n, n);
    }
    // A length-prefixed string of at most `limit` bytes.
    std::string str(size_t limit = kMaxString)
    {
        uint32_t n = u32();
        if (!ok_ || n > limit || !take(n)) {
            ok_ = false;
            return {};
        }
        return std::string(reinterpret_cast<const char *>(p_ - n), n);
    }
    // Everything not read yet.
    std::string rest()
    {
        size_t n = left_;
        if (!take(n))
            return {};
        return std::string(reinterpret_cast<const char *>(p_ - n), n);
    }
    // A count of items each at least `min_item` bytes long: fails early on a count the
    // rest of the buffer could not possibly hold, so no caller reserves absurd memory.
    uint32_t count(size_t min_item) noexcept
    {
        uint32_t n = u32();
        if (ok_ && min_item && n > left_ / min_item)
            ok_ = false;
        return ok_ ? n : 0;
    }
    bool ok() const noexcept { return ok_; }
    // True when everything was read and nothing is left over.
    bool done() const noexcept { return ok_ && left_ == 0; }

private:
    bool take(size_t n) noexcept
    {
        if (!ok_ || n > left_) {
            ok_ = false;
            return false;
        }
        p_ += n;
        left_ -= n;
        return true;
    }
    uint64_t le(int n) noexcept
    {
        if (!take(static_cast<size_t>(n)))
            return 0;
        uint64_t v = 0;
        for (int i = 0; i < n; ++i)
            v |= static_cast<uint64_t>(p_[i - n]) << (8 * i);
        return v;
    }
    const uint8_t *p_;
    size_t left_;
    bool ok_ = true;
};

} // namespace lnd::proto
