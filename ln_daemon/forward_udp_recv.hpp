// The UDP receive thread: reads batches of datagrams from the data socket with recvmmsg,
// authenticates (and decrypts) and validates each, and writes single-fragment samples straight from the receive buffer into
// their ring; larger samples go through the stream's Reassembler first.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <thread>
#include <unordered_map>

#include "forward.hpp"
#include "forward_recv_stream.hpp"

namespace lnd::fwd {

class UdpReceiver {
public:
    // `fd` is the bound data socket (owned by the caller, alive until stop() returned).
    UdpReceiver(int fd, RecvTable &table, TotalCounters &totals, const Options &options);
    ~UdpReceiver();
    UdpReceiver(const UdpReceiver &) = delete;
    UdpReceiver &operator=(const UdpReceiver &) = delete;

    void start();
    // Wakes the thread (shutdown of the socket's receive side) and joins it.
    void stop() noexcept;

private:
    void run();
    // `datagram` is the receive buffer: an encrypted payload is decrypted in place.
    void handle(uint8_t *datagram, size_t size, const Address &from, int64_t now_ns);
    RecvStream *lookup(uint64_t token);
    void sweep(int64_t now_ns);

    const int fd_;
    RecvTable &table_;
    TotalCounters &totals_;
    const int64_t max_idle_ns_;
    const int64_t spin_ns_; // poll the socket this long before blocking
    std::atomic<bool> stop_{false};
    std::thread thread_;
    // Receive thread only: lookups since the table last changed.
    std::unordered_map<uint64_t, std::shared_ptr<RecvStream>> cache_;
    uint64_t cache_generation_ = 0;
};

} // namespace lnd::fwd
