// The receiving end of one stream (RecvStream: the local ring's tap, counters, reassembly)
// and the table the receive threads look streams up in by token (RecvTable).  A stream is
// shared between the table and the threads using it at that moment; close() guarantees that
// nothing is written into the ring after it returns, whoever still holds the object.
#pragma once

#include <atomic>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <shared_mutex>
#include <string>
#include <vector>

#include "forward.hpp"
#include "forward_net.hpp"
#include "forward_reassembly.hpp"
#include "forward_stats.hpp"
#include "forward_tap.hpp"
#include "forward_udp_guard.hpp"

namespace lnd::fwd {

class RecvStream {
public:
    // Opens the ring into `out`, or refuses (error stream_failed).
    static Outcome open(const RecvSpec &spec, const Key &daemon_key, ReassemblyBudget &budget,
                        size_t max_incomplete, std::shared_ptr<RecvStream> &out);
    RecvStream(const RecvSpec &spec, const Key &daemon_key, Tap tap, ReassemblyBudget &budget,
               size_t max_incomplete);

    const RecvSpec spec;
    const Key key; // the stream key (sec::stream_key), for every salt or connection
    StreamCounters counters;
    // Counts a datagram, frame or hello that failed authentication, with why.
    void reject(const std::string &why);

    // Writes a complete sample into the ring and counts it (written, or stale if it is not
    // newer than the ring's newest).  Nothing happens once the stream is closed.
    void write(const uint8_t *data, uint64_t seq, int64_t timestamp_ns);
    // The same in place, for a sample whose bytes are at hand (TCP: all in the socket's
    // buffer): true with *payload, the slot of sample `seq` to fill, and the stream locked
    // (the ring's write lock held) until finish(); false if the stream is closed or the ring
    // refuses (then write() a copy, which counts why).  finish publishes the sample
    // (`intact`) or leaves nothing (a torn frame, a failed read: counted as a drop).
    bool begin(uint64_t seq, void **payload);
    // `counted`: the caller counts a sample left unpublished itself (a rejected frame).
    void finish(bool intact, int64_t timestamp_ns, bool counted = false);
    // The ring's newest sequence number (0 when closed: nothing will be written anyway).
    uint64_t newest();
    void close() noexcept;
    bool closed() const noexcept { return closed_.load(std::memory_order_acquire); }

    // TCP: connections carrying this stream now; `connected` in the stats is "> 0".
    void attach(const std::string &peer);
    void detach() noexcept;

    // UDP receive thread only.
    Reassembler reassembler;
    Address last_source; // to update the peer text only when the source changes
    UdpGuard guard;      // authenticates every datagram before anything else looks at it

private:
    // Counts the outcome of a write into the ring (under mutex_): a sample, a stale one, or a
    // drop with libln's error.
    void count_write(int rc);

    std::mutex mutex_; // serializes the tap: writers are the UDP thread and TCP connections
    Tap tap_;
    std::atomic<bool> closed_{false};
    std::atomic<int> connections_{0};
};

// Streams by token, looked up by the receive threads on every datagram or connection.
// generation() changes with every change of the table, so a thread may cache lookups.
class RecvTable {
public:
    std::shared_ptr<RecvStream> find(uint64_t token) const;
    // Inserts or replaces; returns the stream it replaced, if any.
    std::shared_ptr<RecvStream> put(std::shared_ptr<RecvStream> stream);
    std::shared_ptr<RecvStream> take(uint64_t token);
    std::vector<std::shared_ptr<RecvStream>> all() const;
    uint64_t generation() const noexcept { return generation_.load(std::memory_order_acquire); }

private:
    mutable std::shared_mutex mutex_;
    std::map<uint64_t, std::shared_ptr<RecvStream>> streams_;
    std::atomic<uint64_t> generation_{0};
};

// Counters of the receive side that belong to no stream.
struct TotalCounters {
    std::atomic<uint64_t> unknown_stream{0};
    std::atomic<uint64_t> malformed{0};
};

} // namespace lnd::fwd
