// forward_test.hpp — what the forwarder tests share: rings with names unique to the test
// process, a tap that publishes like a local publisher, one that reads like a subscriber,
// sample patterns that show any torn or misplaced byte, waiting for a condition (the
// deadline only stops a hung test, nothing is timed), and a UDP relay that drops,
// duplicates or passes each datagram by its number.
#ifndef LN_FORWARD_TEST_HPP
#define LN_FORWARD_TEST_HPP

#include <arpa/inet.h>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstring>
#include <functional>
#include <memory>
#include <netinet/in.h>
#include <poll.h>
#include <string>
#include <sys/socket.h>
#include <thread>
#include <unistd.h>
#include <vector>

#include <ln/ln.h>
#include <ln_admin.h>

#include "daemon_test.hpp"
#include "forward.hpp"

namespace fwdtest {

constexpr uint64_t kHash = 0xf0e1d2c3b4a59687ull;

// A ring as the manager would create it; unlinked again by the destructor.
class TestRing {
public:
    TestRing(uint64_t message_size, uint32_t slots, uint64_t layout_hash = kHash)
        : size_(message_size), hash_(layout_hash)
    {
        static std::atomic<int> counter{0};
        name_ = "/ln.fwdtest" + std::to_string(::getpid()) + "." +
                std::to_string(counter.fetch_add(1)) + ".0";
        ln_ring_admin_unlink(name_.c_str());
        int rc = ln_ring_admin_create(&admin_, name_.c_str(), "fwd.topic", "test/fwd", layout_hash,
                                      message_size, slots);
        LN_CHECK_EQ(rc, LN_OK);
        if (rc != LN_OK)
            std::fprintf(stderr, "    %s\n", ln_last_error());
    }
    ~TestRing()
    {
        if (admin_) {
            ln_ring_admin_close(admin_);
            ln_ring_admin_unlink(name_.c_str());
        }
    }
    TestRing(const TestRing &) = delete;
    TestRing &operator=(const TestRing &) = delete;

    const std::string &name() const { return name_; }
    uint64_t size() const { return size_; }
    uint64_t hash() const { return hash_; }
    uint64_t newest() const
    {
        uint64_t seq = 0;
        ln_ring_admin_write_seq(admin_, &seq);
        return seq;
    }

private:
    std::string name_;
    uint64_t size_, hash_;
    ln_ring_admin *admin_ = nullptr;
};

struct TapDeleter {
    void operator()(ln_ring_tap *t) const { ln_ring_tap_close(t); }
};
using TapPtr = std::unique_ptr<ln_ring_tap, TapDeleter>;

inline TapPtr open_tap(const TestRing &ring, unsigned mode)
{
    ln_ring_tap *t = nullptr;
    LN_CHECK_EQ(ln_ring_tap_open(&t, ring.name().c_str(), ring.hash(), ring.size(), mode), LN_OK);
    return TapPtr(t);
}

// Bytes of sample `seq`: every 8-byte word depends on seq and its position.
inline void fill(uint8_t *p, size_t n, uint64_t seq)
{
    uint64_t x = seq * 0x9e3779b97f4a7c15ull + 1;
    for (size_t i = 0; i < n; i += 8) {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        std::memcpy(p + i, &x, n - i < 8 ? n - i : 8);
    }
}

inline bool matches(const uint8_t *p, size_t n, uint64_t seq)
{
    std::vector<uint8_t> want(n);
    fill(want.data(), n, seq);
    return std::memcmp(p, want.data(), n) == 0;
}

inline int64_t stamp(uint64_t seq)
{
    return 1'700'000'000'000'000'000 + static_cast<int64_t>(seq) * 1000 + 7;
}

// Publishes into a ring the way a local publisher would (never waiting for anyone).
class Publisher {
public:
    explicit Publisher(const TestRing &ring)
        : tap_(open_tap(ring, LN_TAP_NEWEST)), buf_(ring.size())
    {}
    int publish(uint64_t seq)
    {
        fill(buf_.data(), buf_.size(), seq);
        return ln_ring_tap_inject(tap_.get(), buf_.data(), seq, stamp(seq));
    }

private:
    TapPtr tap_;
    std::vector<uint8_t> buf_;
};

// Reads every sample a ring gets, like a queued subscriber.
class Reader {
public:
    explicit Reader(const TestRing &ring) : buf(ring.size()), tap_(open_tap(ring, LN_TAP_EVERY)) {}
    // LN_OK with info and buf filled, or LN_ETIMEOUT.
    int read(double timeout) { return ln_ring_tap_read(tap_.get(), buf.data(), &info, timeout); }

    ln_sample_info info = {};
    std::vector<uint8_t> buf;

private:
    TapPtr tap_;
};

// Polls `done` until it holds or `seconds` passed (then the caller's check fails).
template <class F>
bool wait_until(F done, double seconds = 30)
{
    auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    while (!done()) {
        if (std::chrono::steady_clock::now() > deadline)
            return false;
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    return true;
}

inline lnd::fwd::StreamStats stats_of(const lnd::fwd::Forwarder &f, uint64_t token, bool sending)
{
    for (const auto &s : f.stats())
        if (s.token == token && s.sending == sending)
            return s;
    lnd::fwd::StreamStats none;
    none.token = 0;
    return none;
}

inline lnd::fwd::Options local_options()
{
    lnd::fwd::Options o;
    o.bind_address = "127.0.0.1";
    o.data_port = 0;
    return o;
}

inline lnd::fwd::SendSpec send_spec(uint64_t token, const TestRing &ring, lnd::fwd::Transport t,
                                    uint16_t port,
                                    lnd::fwd::Level level = lnd::fwd::Level::authenticate)
{
    lnd::fwd::SendSpec s;
    s.security = level;
    s.token = token;
    s.ring = ring.name();
    s.layout_hash = ring.hash();
    s.message_size = ring.size();
    s.transport = t;
    s.host = "127.0.0.1";
    s.port = port;
    return s;
}

// Level none for the tests that hand-craft datagrams and frames without tags.
inline lnd::fwd::RecvSpec recv_spec(uint64_t token, const TestRing &ring, lnd::fwd::Transport t,
                                    lnd::fwd::Level level = lnd::fwd::Level::authenticate)
{
    lnd::fwd::RecvSpec r;
    r.token = token;
    r.ring = ring.name();
    r.layout_hash = ring.hash();
    r.message_size = ring.size();
    r.transport = t;
    r.security = level;
    return r;
}

inline sockaddr_in loopback(uint16_t port)
{
    sockaddr_in a = {};
    a.sin_family = AF_INET;
    a.sin_port = htons(port);
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    return a;
}

inline uint16_t local_port(int fd)
{
    sockaddr_in a = {};
    socklen_t len = sizeof a;
    ::getsockname(fd, reinterpret_cast<sockaddr *>(&a), &len);
    return ntohs(a.sin_port);
}

// A UDP socket on 127.0.0.1 for sending crafted datagrams.
class UdpSocket {
public:
    UdpSocket() : fd_(::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0))
    {
        sockaddr_in a = loopback(0);
        ::bind(fd_, reinterpret_cast<sockaddr *>(&a), sizeof a);
    }
    ~UdpSocket() { ::close(fd_); }
    UdpSocket(const UdpSocket &) = delete;
    UdpSocket &operator=(const UdpSocket &) = delete;
    void send_to(uint16_t port, const void *data, size_t n) const
    {
        sockaddr_in a = loopback(port);
        LN_CHECK_EQ(::sendto(fd_, data, n, 0, reinterpret_cast<sockaddr *>(&a), sizeof a),
                    static_cast<ssize_t>(n));
    }
    int fd() const { return fd_; }

private:
    int fd_;
};

// Receives on its own port and passes datagram number n (from 1) on to `target`
// `copies(n)` times: 0 drops it, 2 duplicates it.
class UdpRelay {
public:
    UdpRelay(uint16_t target, std::function<int(uint64_t)> copies)
        : target_(target), copies_(std::move(copies)), thread_([this] { run(); })
    {}
    ~UdpRelay()
    {
        stop_ = true;
        thread_.join();
    }
    uint16_t port() const { return local_port(in_.fd()); }
    uint64_t seen() const { return seen_.load(); }

private:
    void run()
    {
        std::vector<uint8_t> buf(65536);
        while (!stop_) {
            pollfd p = {in_.fd(), POLLIN, 0};
            if (::poll(&p, 1, 20) <= 0)
                continue;
            ssize_t n = ::recv(in_.fd(), buf.data(), buf.size(), 0);
            if (n < 0)
                continue;
            uint64_t number = seen_ + 1;
            for (int i = copies_(number); i > 0; --i)
                out_.send_to(target_, buf.data(), static_cast<size_t>(n));
            seen_ = number;
        }
    }

    UdpSocket in_, out_;
    uint16_t target_;
    std::function<int(uint64_t)> copies_;
    std::atomic<uint64_t> seen_{0};
    std::atomic<bool> stop_{false};
    std::thread thread_;
};

} // namespace fwdtest

#endif // LN_FORWARD_TEST_HPP
