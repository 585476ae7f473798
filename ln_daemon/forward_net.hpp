// Socket plumbing of the forwarder: the stop signal every blocking wait also watches, name
// resolution, address text, buffer sizes, binding the data sockets, and waiting on or
// reading/writing a socket without ever blocking past a stop.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <string>
#include <sys/socket.h>
#include <sys/uio.h>
#include <vector>

#include "fd.hpp"
#include "outcome.hpp"

namespace lnd::fwd {

// A one-shot stop request: an atomic flag for loops that poll it, and an eventfd that
// becomes readable for good, for threads waiting in poll().
class StopSignal {
public:
    StopSignal(); // throws std::system_error if no eventfd can be made
    void raise() noexcept;
    bool raised() const noexcept { return raised_.load(std::memory_order_acquire); }
    int fd() const noexcept { return fd_.get(); }
    // Sleeps up to `us` microseconds; true if the stop was raised (before or meanwhile).
    bool sleep_us(int64_t us) const noexcept;
    bool sleep_for(int ms) const noexcept { return sleep_us(int64_t(ms) * 1000); }

private:
    std::atomic<bool> raised_{false};
    UniqueFd fd_;
};

struct Address {
    sockaddr_storage storage{};
    socklen_t length = 0;
    int family() const noexcept { return storage.ss_family; }
    const sockaddr *get() const noexcept { return reinterpret_cast<const sockaddr *>(&storage); }
};

// All addresses of host:port for `socktype` (SOCK_DGRAM/SOCK_STREAM) into `out`; refused
// with error stream_failed and the reason.
Outcome resolve(const std::string &host, uint16_t port, int socktype, std::vector<Address> &out);
// "1.2.3.4:5" or "[::1]:5"; IPv4-mapped IPv6 addresses are shown as IPv4.
std::string address_text(const sockaddr *sa);
// SO_RCVBUFFORCE/SO_SNDBUFFORCE (allowed with CAP_NET_ADMIN), else the capped
// SO_RCVBUF/SO_SNDBUF.
void set_buffer_sizes(int fd, int bytes) noexcept;

// The UDP socket and the TCP listener of the data port: same port number, close-on-exec.
// The UDP socket blocks (with a receive timeout of kUdpReceiveTimeoutMs; shutdown() wakes
// it), the listener does not (its thread polls it together with a StopSignal).
constexpr int kUdpReceiveTimeoutMs = 100;

struct DataSockets {
    UniqueFd udp;
    UniqueFd tcp;
    uint16_t port = 0;
};
// `bind_address` "" binds every interface (IPv6 and IPv4 when the host has IPv6);
// `port` 0 picks a number free for both.  Throws std::system_error with the reason.
DataSockets bind_data_sockets(const std::string &bind_address, uint16_t port, int buffer);

enum class Wait { ready, timeout, stopped };
// Waits up to `timeout_ms` (< 0: forever) for `events` on fd or for the stop; errors and
// hang-ups count as ready (the next call on fd reports them).
Wait wait_fd(int fd, short events, const StopSignal &stop, int timeout_ms) noexcept;

// Result of a full read or write on a non-blocking stream socket.
enum class Io { ok, closed, error, timeout, stopped };
// One read of up to n bytes without waiting: Io::ok with got > 0 bytes read, Io::timeout if
// none are buffered (wait for POLLIN, then try again), Io::closed at the end of the stream,
// Io::error with errno's text in `error`.
Io recv_some(int fd, void *buf, size_t n, size_t &got, std::string &error);
// Reads exactly n bytes (timeout_ms < 0: no deadline).  `error` gets errno's text.
// spin_ns > 0: poll (yielding the CPU) that long before sleeping in poll().
Io read_full(int fd, void *buf, size_t n, const StopSignal &stop, int timeout_ms,
             std::string &error, int64_t spin_ns = 0);
// Writes the whole iovec array (it is advanced in place), watching fd for the peer's close
// while it waits for room.  A peer sends nothing after its reply, so anything readable
// while writing means it closed or broke the stream.
Io write_full(int fd, iovec *iov, int count, const StopSignal &stop, std::string &error);

} // namespace lnd::fwd
