// PullPort: one UDP socket on (address, port), shared by every pull topic served on it
// (docs/daemon.md, "Pull topics").  Its receive thread decodes each datagram (bare or in an
// NDNLPv2 LpPacket), dispatches an Interest to the topic with the longest name prefix and
// lets it answer, and expires parked Interests on time (it polls with a timeout until the
// next expiry).  A datagram that is not a well-formed Interest for a served name is counted
// and dropped; it never reaches a topic.  Fixed buffers: one datagram in, one reply out.
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "fd.hpp"
#include "forward_net.hpp"
#include "outcome.hpp"
#include "pull_messages.hpp"
#include "pull_reply.hpp"
#include "pull_topic.hpp"

namespace lnd {

constexpr size_t kPullRxBytes = 9000; // the largest datagram decoded (a jumbo frame)
constexpr int kPullIdlePollMs = 1000; // the receive thread's poll timeout with nothing parked
constexpr int kPullBatch = 64;        // datagrams per wake-up before expiring parked ones

class PullPort {
public:
    // Binds a UDP socket to address:port (a numeric IPv4 or IPv6 address; port 0 lets the
    // kernel pick one, which only tests do) and starts the receive thread, into `out`.
    static Outcome open(const std::string &address, uint16_t port, std::unique_ptr<PullPort> &out);
    ~PullPort(); // stops and joins the thread, closes the socket
    PullPort(const PullPort &) = delete;
    PullPort &operator=(const PullPort &) = delete;

    const std::string &address() const noexcept { return address_; }
    uint16_t port() const noexcept { return port_; } // the bound port
    int fd() const noexcept { return fd_.get(); }

    // The poll loop: the topics the thread dispatches to (by topic->config().name, which
    // must not change while attached).
    void attach(PullTopic *topic);
    void detach(PullTopic *topic);
    // The attached topic (other than `except`) serving exactly `name`, or nullptr.
    const PullTopic *serving(const std::vector<uint8_t> &name, const PullTopic *except) const;
    size_t topics() const;

    PullPortStatus status() const;

private:
    struct Entry {
        std::vector<uint8_t> name;
        PullTopic *topic;
    };

    PullPort(std::string address, uint16_t port, UniqueFd fd);
    void loop();
    void receive(const uint8_t *buf, size_t size, const PullPeer &peer);
    // Under mutex_: the topic whose name is the longest prefix of `name`, or nullptr.
    const Entry *route(ln_ndn_bytes name) const noexcept;
    void count(uint64_t PullPortCounters::*which) noexcept;
    void set_error(const ErrorText &e) noexcept;

    const std::string address_;
    const uint16_t port_;
    UniqueFd fd_;
    fwd::StopSignal stop_;
    std::vector<uint8_t> rx_;
    PullSender sender_; // the receive thread's

    mutable std::mutex mutex_; // guards entries_; the thread holds it while it answers
    std::vector<Entry> entries_;

    mutable std::mutex stats_mutex_; // guards the two below
    PullPortCounters counters_;
    ErrorText error_;

    std::thread thread_; // last: starts once everything above exists
};

} // namespace lnd
