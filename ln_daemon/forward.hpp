// Host-to-host topic forwarding (docs/network.md): the daemon of a publisher's host reads a
// topic's ring through a tap and sends every sample to the daemons of hosts with
// subscribers, over UDP (fragmented, newest sample wins) or TCP (in order, bounded queue);
// the receiving daemon reassembles and writes samples into its local ring under their
// original sequence numbers and timestamps.  Streams are identified by a random 64-bit
// token the manager hands to both ends; every counter is kept per stream.  Every datagram and
// frame is authenticated (or also encrypted) under a key derived per stream from the daemon
// key (forward_crypto.hpp), unless the stream's security level is none.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "auth.hpp"
#include "forward_crypto.hpp"
#include "outcome.hpp"

namespace lnd::fwd {

enum class Transport : uint8_t { udp = 0, tcp = 1 };
using sec::Level;

// Where one topic's samples go from this host.
struct SendSpec {
    uint64_t token = 0; // identifies the stream on the wire and in stats
    std::string ring;   // shm name of the local ring to read
    uint64_t layout_hash = 0;
    uint64_t message_size = 0;
    Transport transport = Transport::udp;
    std::string host; // receiving daemon: address and data port
    uint16_t port = 0;
    Level security = Level::authenticate;
};

// Which local ring one incoming stream is written into.
struct RecvSpec {
    uint64_t token = 0;
    std::string ring;
    uint64_t layout_hash = 0;
    uint64_t message_size = 0;
    Transport transport = Transport::udp;
    Level security = Level::authenticate;
};

struct StreamStats {
    uint64_t token = 0;
    bool sending = false; // true: this host sends, false: it receives
    Transport transport = Transport::udp;
    std::string ring;       // current segment name (follows successors)
    std::string peer;       // sender: "host:port" it sends to; receiver: last source seen
    uint64_t samples = 0;   // sent / written into the ring
    uint64_t bytes = 0;     // payload bytes sent / received
    uint64_t drops = 0;     // sender: samples not sent (ring overrun, queue full, send error);
                            // receiver: incomplete samples given up
    uint64_t stale = 0;     // receiver: samples not newer than the ring's newest (duplicates,
                            // reordered)
    uint64_t invalid = 0;   // receiver: malformed datagrams/frames for this stream
    uint64_t rejected = 0;  // receiver: datagrams/frames/hellos that failed authentication
                            // (forged, replayed, truncated, too old, wrong key or level)
    bool connected = true;  // TCP: connection up (UDP: always true)
    std::string last_error; // most recent problem, "" if none
};

struct Options {
    std::string bind_address;                 // "" = all interfaces
    uint16_t data_port = 0;                   // UDP and TCP data port; 0 = ephemeral
    size_t udp_payload = 1368;                // payload bytes per datagram (fragment)
    size_t udp_max_incomplete = 4;            // samples being reassembled per stream, at most
    size_t udp_reassembly_bytes = 256u << 20; // memory of all reassembly buffers, at most
    double udp_incomplete_timeout = 1.0;      // seconds without a fragment before an
                                              // incomplete sample is given up
    double udp_max_rate = 0;                  // bytes/s per UDP sending stream (datagrams
                                              // with headers), bursts of 64 KiB; 0: no limit
    int socket_buffer = 64 << 20;             // SO_RCVBUF(FORCE)/SO_SNDBUF wanted
    size_t tcp_queue_samples = 1024;          // per TCP sending stream, at most (with the
    size_t tcp_queue_bytes = 256u << 20;      // sample being sent; one read buffer on top)
    // Senders and receivers: poll (yielding the CPU) for up to this many microseconds for
    // the next sample / datagram / frame before sleeping, which saves a wake-up per hop on
    // hosts with CPUs to spare; 0 sleeps at once.
    unsigned spin_us = 0;
    Key key; // the daemon key every stream key is derived from (set_key() replaces it)
};

// Global counters of the receive side that belong to no stream.
struct Totals {
    uint64_t unknown_stream = 0;   // datagrams/connections with a token no RecvSpec has
    uint64_t malformed = 0;        // datagrams/frames that do not parse at all
    uint64_t reassembly_bytes = 0; // memory held by incomplete UDP samples now
    uint64_t reassembly_peak = 0;  // the most it ever held (<= udp_reassembly_bytes)
};

// Owns the data sockets and every stream's threads.  Thread-safe: the daemon's poll loop
// calls it while stream threads run.
class Forwarder {
public:
    // Binds the UDP and TCP data sockets (throws std::system_error with a clear text, also
    // with EINVAL for options that cannot work).
    explicit Forwarder(const Options &options);
    ~Forwarder(); // stops and joins every thread
    Forwarder(const Forwarder &) = delete;
    Forwarder &operator=(const Forwarder &) = delete;

    uint16_t data_port() const;
    // Add or replace (same token) a stream; refused with error stream_failed and why (bad ring,
    // ...).
    // Replacing or removing a sending stream joins its threads first, which can take up to
    // ~0.1 s (their ring wait).  Names are resolved by the stream's threads, never here.
    Outcome set_send(const SendSpec &spec);
    Outcome set_recv(const RecvSpec &spec);
    // Stop and forget a stream (sending and receiving with that token); false if there is
    // none.  Once it returned nothing more is sent or written into the ring for it.
    bool remove(uint64_t token);
    std::vector<StreamStats> stats() const;
    // A new daemon key: every stream is started again (new salts, new connections) with keys
    // derived from it; samples in flight meanwhile may be lost.  The first stream that could
    // not start again says why (the others did).
    Outcome set_key(const Key &key);
    Totals totals() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

} // namespace lnd::fwd
