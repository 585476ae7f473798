// The daemon's wire protocol (docs/daemon.md, "Protocol"): frame layout, message and error
// numbers, and the little-endian Writer/Reader every message is built and parsed with.
// A Reader never reads past its buffer: the first short read marks it failed, and the
// caller checks ok() once at the end.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>

namespace lnd::proto {

constexpr uint16_t kVersion = 1;
constexpr char kMagic[8] = {'L', 'N', 'D', 'A', 'E', 'M', 'O', 'N'};
constexpr size_t kLengthBytes = 4;
constexpr size_t kHeaderBytes = 5; // type u8 + request id u32
constexpr size_t kTagBytes = 32;
constexpr size_t kNonceBytes = 32;
constexpr size_t kMaxFrame = 4u << 20; // most bytes after the length field
constexpr size_t kMaxName = 255;       // instance and process names
// The longest CLIENT_HELLO (type, request id, magic, version, nonce, instance, proof): before
// the handshake no frame may be longer, so an unauthenticated peer costs a few hundred bytes.
constexpr size_t kMaxHelloFrame = kHeaderBytes + sizeof kMagic + 2 + kNonceBytes + 4 + kMaxName +
                                  32;
static_assert(kMaxHelloFrame == 338);

enum class Msg : uint8_t {
    daemon_hello = 0x01,
    client_hello = 0x02,
    auth_ok = 0x03,
    spawn = 0x10,
    stop = 0x11,
    signal = 0x12,
    list = 0x13,
    output = 0x14,
    forget = 0x15,
    ping = 0x16,
    net_info = 0x40, // rings and forwarding (docs/daemon.md, "Rings and forwarding")
    ring_create = 0x41,
    ring_retire = 0x42,
    ring_reader = 0x43,
    ring_counts = 0x44,
    ring_remove = 0x45,
    ring_purge = 0x46,
    ring_seq = 0x47,
    stream_send = 0x48,
    stream_recv = 0x49,
    stream_remove = 0x4a,
    stream_stats = 0x4b,
    logger_topic = 0x4c, // topic logging (docs/daemon.md, "Topic logging")
    logger_remove = 0x4d,
    logger_enable = 0x4e,
    logger_fetch = 0x4f,
    logger_status = 0x50,
    pull_topic = 0x51, // pull topics over NDN (docs/daemon.md, "Pull topics")
    pull_remove = 0x52,
    pull_status = 0x53,
    ok = 0x20,
    error = 0x21,
    spawned = 0x22,
    process_list = 0x23,
    output_lines = 0x24,
    net_details = 0x25, // reply to NET_INFO
    value = 0x26,       // u64 reply to RING_PURGE and RING_SEQ
    stream_list = 0x27, // reply to STREAM_STATS
    logger_data = 0x28, // reply to LOGGER_FETCH
    logger_list = 0x29, // reply to LOGGER_STATUS
    pull_list = 0x2a,   // reply to PULL_STATUS
    ev_output = 0x30,
    ev_exited = 0x31,
    ev_state = 0x32,
};

enum class Err : uint16_t {
    bad_request = 1,       // malformed or invalid request; the connection is closed
    not_authenticated = 2, // a request before authentication; the connection is closed
    auth_failed = 3,       // wrong key (or instance name); the connection is closed
    version = 4,           // unsupported protocol version; the connection is closed
    unknown_process = 5,
    already_running = 6,
    not_running = 7,
    still_running = 8, // FORGET of a process that has not exited
    spawn_failed = 9,
    invalid_spec = 10, // a SPAWN field the daemon refuses before starting anything
    limit = 11,        // too many processes
    os_error = 12,     // a system call failed (kill, ...)
    ring_failed = 13,    // a ring request refused, or libln failed (ln_last_error's text)
    stream_failed = 14,  // the forwarder refused a stream (its text)
    unknown_stream = 15, // STREAM_REMOVE of a token this instance has no stream for
    logger_failed = 16,  // a logger request refused (no such logger, memory limit, ...)
    pull_failed = 16,    // a pull topic request refused (the same number as logger_failed)
};

enum class Stream : uint8_t { pty = 0, out = 1, err = 2 };
enum class ExitKind : uint8_t { none = 0, code = 1, signal = 2 };

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
    {
    }
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
    std::string str(size_t limit = kMaxFrame)
    {
        uint32_t n = u32();
        if (!ok_ || n > limit || !take(n)) {
            ok_ = false;
            return {};
        }
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
