// Socket plumbing of the forwarder (forward_net.hpp).  Every wait here polls the stream's
// StopSignal too, so no thread of the forwarder can hang in a system call past a stop.
#include "forward_net.hpp"

#include <arpa/inet.h>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <ctime>
#include <netdb.h>
#include <netinet/in.h>
#include <poll.h>
#include <thread>
#include <sys/eventfd.h>
#include <system_error>
#include <unistd.h>

namespace lnd::fwd {

namespace {

using Clock = std::chrono::steady_clock;

int ms_left(Clock::time_point deadline) noexcept
{
    auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
    return left.count() < 0 ? 0 : static_cast<int>(left.count());
}

[[noreturn]] void throw_errno(int err, const std::string &what)
{
    throw std::system_error(err, std::generic_category(), what);
}

void set_port(Address &a, uint16_t port) noexcept
{
    if (a.family() == AF_INET6)
        reinterpret_cast<sockaddr_in6 &>(a.storage).sin6_port = htons(port);
    else
        reinterpret_cast<sockaddr_in &>(a.storage).sin_port = htons(port);
}

uint16_t bound_port(int fd) noexcept
{
    Address a;
    a.length = sizeof a.storage;
    if (::getsockname(fd, reinterpret_cast<sockaddr *>(&a.storage), &a.length) != 0)
        return 0;
    return ntohs(a.family() == AF_INET6
                     ? reinterpret_cast<const sockaddr_in6 &>(a.storage).sin6_port
                     : reinterpret_cast<const sockaddr_in &>(a.storage).sin_port);
}

// Where "" binds: the IPv6 wildcard (dual-stack) if this host can make IPv6 sockets.
Address wildcard_address()
{
    Address a;
    UniqueFd probe(::socket(AF_INET6, SOCK_DGRAM | SOCK_CLOEXEC, 0));
    if (probe) {
        auto &in6 = reinterpret_cast<sockaddr_in6 &>(a.storage);
        in6.sin6_family = AF_INET6;
        in6.sin6_addr = in6addr_any;
        a.length = sizeof in6;
    } else {
        auto &in = reinterpret_cast<sockaddr_in &>(a.storage);
        in.sin_family = AF_INET;
        in.sin_addr.s_addr = htonl(INADDR_ANY);
        a.length = sizeof in;
    }
    return a;
}

// A socket of `type` bound to `where`; errno set and an empty fd on failure.
UniqueFd bound_socket(const Address &where, int type)
{
    UniqueFd fd(::socket(where.family(), type | SOCK_CLOEXEC, 0));
    if (!fd)
        return fd;
    int one = 1, zero = 0;
    if (type & SOCK_STREAM)
        ::setsockopt(fd.get(), SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    if (where.family() == AF_INET6 &&
        IN6_IS_ADDR_UNSPECIFIED(&reinterpret_cast<const sockaddr_in6 &>(where.storage).sin6_addr))
        ::setsockopt(fd.get(), IPPROTO_IPV6, IPV6_V6ONLY, &zero, sizeof zero);
    if (::bind(fd.get(), where.get(), where.length) != 0) {
        int err = errno;
        fd.reset();
        errno = err;
    }
    return fd;
}

} // namespace

// ---- StopSignal ------------------------------------------------------------------------------

StopSignal::StopSignal() : fd_(::eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK))
{
    if (!fd_)
        throw_errno(errno, "cannot create an eventfd");
}

void StopSignal::raise() noexcept
{
    raised_.store(true, std::memory_order_release);
    uint64_t one = 1;
    ssize_t rc = ::write(fd_.get(), &one, sizeof one); // never read back: stays readable
    (void)rc;
}

bool StopSignal::sleep_us(int64_t us) const noexcept
{
    auto deadline = Clock::now() + std::chrono::microseconds(us);
    while (!raised()) {
        auto left = std::chrono::duration_cast<std::chrono::nanoseconds>(deadline - Clock::now());
        if (left.count() <= 0)
            break;
        timespec ts = {static_cast<time_t>(left.count() / 1'000'000'000),
                       static_cast<long>(left.count() % 1'000'000'000)};
        pollfd p = {fd_.get(), POLLIN, 0};
        if (::ppoll(&p, 1, &ts, nullptr) > 0)
            break;
    }
    return raised();
}

// ---- addresses -------------------------------------------------------------------------------

Outcome resolve(const std::string &host, uint16_t port, int socktype, std::vector<Address> &out)
{
    addrinfo hints = {};
    hints.ai_family = AF_UNSPEC;
    hints.ai_socktype = socktype;
    hints.ai_flags = AI_NUMERICSERV;
    addrinfo *res = nullptr;
    std::string service = std::to_string(port);
    int rc = ::getaddrinfo(host.c_str(), service.c_str(), &hints, &res);
    if (rc != 0)
        return outcome::error(proto::Err::stream_failed,
                              "cannot resolve '" + host + "': " +
                                  (rc == EAI_SYSTEM ? std::strerror(errno) : ::gai_strerror(rc)));
    out.clear();
    for (addrinfo *ai = res; ai; ai = ai->ai_next) {
        if (ai->ai_addrlen > sizeof(sockaddr_storage))
            continue;
        Address a;
        std::memcpy(&a.storage, ai->ai_addr, ai->ai_addrlen);
        a.length = ai->ai_addrlen;
        out.push_back(a);
    }
    ::freeaddrinfo(res);
    if (out.empty())
        return outcome::error(proto::Err::stream_failed, "no usable address for '" + host + "'");
    return outcome::ok();
}

std::string address_text(const sockaddr *sa)
{
    char host[INET6_ADDRSTRLEN] = "?";
    unsigned port = 0;
    if (sa->sa_family == AF_INET) {
        const auto *in = reinterpret_cast<const sockaddr_in *>(sa);
        ::inet_ntop(AF_INET, &in->sin_addr, host, sizeof host);
        port = ntohs(in->sin_port);
    } else if (sa->sa_family == AF_INET6) {
        const auto *in6 = reinterpret_cast<const sockaddr_in6 *>(sa);
        port = ntohs(in6->sin6_port);
        if (IN6_IS_ADDR_V4MAPPED(&in6->sin6_addr)) {
            ::inet_ntop(AF_INET, &in6->sin6_addr.s6_addr[12], host, sizeof host);
        } else {
            ::inet_ntop(AF_INET6, &in6->sin6_addr, host, sizeof host);
            return "[" + std::string(host) + "]:" + std::to_string(port);
        }
    }
    return std::string(host) + ":" + std::to_string(port);
}

void set_buffer_sizes(int fd, int bytes) noexcept
{
    if (bytes <= 0)
        return;
    if (::setsockopt(fd, SOL_SOCKET, SO_RCVBUFFORCE, &bytes, sizeof bytes) != 0)
        ::setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &bytes, sizeof bytes);
    if (::setsockopt(fd, SOL_SOCKET, SO_SNDBUFFORCE, &bytes, sizeof bytes) != 0)
        ::setsockopt(fd, SOL_SOCKET, SO_SNDBUF, &bytes, sizeof bytes);
}

DataSockets bind_data_sockets(const std::string &bind_address, uint16_t port, int buffer)
{
    Address where;
    if (bind_address.empty()) {
        where = wildcard_address();
    } else {
        addrinfo hints = {};
        hints.ai_family = AF_UNSPEC;
        hints.ai_socktype = SOCK_DGRAM;
        hints.ai_flags = AI_PASSIVE;
        addrinfo *res = nullptr;
        int rc = ::getaddrinfo(bind_address.c_str(), nullptr, &hints, &res);
        if (rc != 0)
            throw std::system_error(EINVAL, std::generic_category(),
                                    "cannot resolve data bind address '" + bind_address +
                                        "': " + ::gai_strerror(rc));
        std::memcpy(&where.storage, res->ai_addr, res->ai_addrlen);
        where.length = res->ai_addrlen;
        ::freeaddrinfo(res);
    }
    std::string name = bind_address.empty() ? "*" : bind_address;
    // With port 0 the kernel picks the TCP port; UDP may hold that number already, so a few
    // more picks are tried before giving up.
    for (int attempt = 0;; ++attempt) {
        set_port(where, port);
        DataSockets s;
        s.tcp = bound_socket(where, SOCK_STREAM | SOCK_NONBLOCK);
        if (s.tcp)
            set_buffer_sizes(s.tcp.get(), buffer); // accepted connections inherit them
        if (!s.tcp || ::listen(s.tcp.get(), 128) != 0)
            throw_errno(errno,
                        "cannot listen for TCP data on " + name + ":" + std::to_string(port));
        s.port = bound_port(s.tcp.get());
        Address udp_where = where;
        set_port(udp_where, s.port);
        s.udp = bound_socket(udp_where, SOCK_DGRAM);
        if (!s.udp) {
            if (errno == EADDRINUSE && port == 0 && attempt < 32)
                continue;
            throw_errno(errno, "cannot bind the UDP data socket to " + name + ":" +
                                   std::to_string(s.port));
        }
        set_buffer_sizes(s.udp.get(), buffer);
        timeval tv = {0, kUdpReceiveTimeoutMs * 1000};
        ::setsockopt(s.udp.get(), SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
        return s;
    }
}

// ---- waiting and stream I/O ------------------------------------------------------------------

Wait wait_fd(int fd, short events, const StopSignal &stop, int timeout_ms) noexcept
{
    auto deadline = Clock::now() + std::chrono::milliseconds(timeout_ms < 0 ? 0 : timeout_ms);
    for (;;) {
        if (stop.raised())
            return Wait::stopped;
        pollfd p[2] = {{fd, events, 0}, {stop.fd(), POLLIN, 0}};
        int n = ::poll(p, 2, timeout_ms < 0 ? -1 : ms_left(deadline));
        if (n < 0) {
            if (errno == EINTR)
                continue;
            return Wait::ready; // let the caller's next call report the problem
        }
        if (p[1].revents)
            return Wait::stopped;
        if (p[0].revents)
            return Wait::ready;
        if (n == 0)
            return Wait::timeout;
    }
}

Io recv_some(int fd, void *buf, size_t n, size_t &got, std::string &error)
{
    for (;;) {
        ssize_t r = ::recv(fd, buf, n, MSG_DONTWAIT);
        if (r > 0) {
            got = static_cast<size_t>(r);
            return Io::ok;
        }
        if (r == 0)
            return Io::closed;
        if (errno == EINTR)
            continue;
        if (errno == EAGAIN || errno == EWOULDBLOCK)
            return Io::timeout;
        error = std::strerror(errno);
        return Io::error;
    }
}

Io read_full(int fd, void *buf, size_t n, const StopSignal &stop, int timeout_ms,
             std::string &error, int64_t spin_ns)
{
    auto *p = static_cast<uint8_t *>(buf);
    auto deadline = Clock::now() + std::chrono::milliseconds(timeout_ms < 0 ? 0 : timeout_ms);
    auto spin_until = Clock::now() + std::chrono::nanoseconds(spin_ns);
    while (n > 0) {
        size_t got = 0;
        Io io = recv_some(fd, p, n, got, error);
        if (io == Io::ok) {
            p += got;
            n -= got;
            continue;
        }
        if (io != Io::timeout)
            return io;
        if (spin_ns > 0 && Clock::now() < spin_until && !stop.raised()) {
            std::this_thread::yield(); // data that comes soon is taken without a wake-up
            continue;
        }
        switch (wait_fd(fd, POLLIN, stop, timeout_ms < 0 ? -1 : ms_left(deadline))) {
        case Wait::stopped:
            return Io::stopped;
        case Wait::timeout:
            return Io::timeout;
        case Wait::ready:
            break;
        }
    }
    return Io::ok;
}

Io write_full(int fd, iovec *iov, int count, const StopSignal &stop, std::string &error)
{
    while (count > 0) {
        if (iov->iov_len == 0) {
            ++iov;
            --count;
            continue;
        }
        msghdr msg = {};
        msg.msg_iov = iov;
        msg.msg_iovlen = static_cast<size_t>(count);
        ssize_t sent = ::sendmsg(fd, &msg, MSG_NOSIGNAL | MSG_DONTWAIT);
        if (sent >= 0) {
            auto left = static_cast<size_t>(sent);
            while (count > 0 && left >= iov->iov_len) {
                left -= iov->iov_len;
                ++iov;
                --count;
            }
            if (count > 0) {
                iov->iov_base = static_cast<uint8_t *>(iov->iov_base) + left;
                iov->iov_len -= left;
            }
            continue;
        }
        if (errno == EINTR)
            continue;
        if (errno != EAGAIN && errno != EWOULDBLOCK) {
            error = std::strerror(errno);
            return Io::error;
        }
        if (wait_fd(fd, POLLOUT | POLLIN, stop, -1) == Wait::stopped)
            return Io::stopped;
        char byte;
        ssize_t peek = ::recv(fd, &byte, 1, MSG_PEEK | MSG_DONTWAIT);
        if (peek == 0)
            return Io::closed;
        if (peek > 0) {
            error = "the receiver sent unexpected data";
            return Io::error;
        }
        if (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) {
            error = std::strerror(errno);
            return Io::error;
        }
    }
    return Io::ok;
}

} // namespace lnd::fwd
