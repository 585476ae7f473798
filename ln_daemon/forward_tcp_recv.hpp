// The TCP receive side: an accept thread on the data port's listener and one thread per
// connection, which reads the hello, answers accept or reject, then reads frames and
// writes them into the stream's ring (a large one straight into a slot as it arrives).
// What the bytes mean is decided by TcpSession (forward_tcp_frame.hpp).
#pragma once

#include <atomic>
#include <cstdint>
#include <list>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "fd.hpp"
#include "forward_net.hpp"
#include "forward_recv_stream.hpp"
#include "forward_tcp_frame.hpp"
#include "forward_wire.hpp"

namespace lnd::fwd {

constexpr size_t kMaxTcpConnections = 256;

class TcpReceiver {
public:
    // `listener` is the non-blocking listening socket (owned by the caller, alive until
    // stop() returned).
    // spin_us: a connection polls that long for the next frame before it sleeps.
    TcpReceiver(int listener, RecvTable &table, TotalCounters &totals, unsigned spin_us = 0);
    ~TcpReceiver();
    TcpReceiver(const TcpReceiver &) = delete;
    TcpReceiver &operator=(const TcpReceiver &) = delete;

    void start();
    // Stops accepting, closes every connection and joins all threads.
    void stop() noexcept;
    // Closes the connections that carry stream `token` and joins their threads (the stream
    // was removed or replaced; a sender reconnects to the new one).
    void drop_stream(uint64_t token) noexcept;

private:
    struct Connection {
        UniqueFd fd;
        std::string peer;
        std::atomic<uint64_t> token{0}; // set once the hello was read
        std::atomic<bool> done{false};
        std::thread thread;
        // The connection thread's: how much more of a large frame wakes it (a part of the
        // receive buffer, at most kWakeBytes), and the socket's SO_RCVLOWAT now.
        size_t wake_bytes = 1;
        int mark = 1;
    };

    void accept_loop();
    void serve(Connection &c);
    // Reads bytes [got, n) of buf while the ring's lock is held, as they arrive: Io::ok, or
    // Io::timeout if nothing came for kStallMs (`got` says how far it came), or how the
    // connection ended.  `feed`: gets each piece as it comes (TcpSession::part).
    Io read_held(Connection &c, uint8_t *buf, size_t n, size_t &got, std::string &error,
                 TcpSession *feed = nullptr);
    // Reads one frame into the ring (in place: straight into a slot as it arrives, else
    // through `payload`); false once the connection is to end.
    bool receive_frame(Connection &c, RecvStream &s, TcpSession &session, uint8_t *payload,
                       bool in_place);
    // Counts and records a frame's verdict; false if the connection is to end.
    static bool judged(const Connection &c, RecvStream &s, TcpSession::Frame verdict);
    static bool ended(const Connection &c, RecvStream &s, Io io, const std::string &error);
    void reap(); // joins connections whose thread ended

    const int listener_;
    RecvTable &table_;
    TotalCounters &totals_;
    const int64_t spin_ns_;
    StopSignal stop_;
    std::thread acceptor_;
    std::mutex mutex_;
    std::list<std::unique_ptr<Connection>> connections_;
};

} // namespace lnd::fwd
