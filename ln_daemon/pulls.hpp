// The daemon's pull topics (docs/daemon.md, "Pull topics"): the PULL_* requests, the table of
// served topics by (instance, topic) and the UDP ports they share, opened with their first
// topic and closed with their last.  Pull topics belong to their instance, not to a
// connection: they keep serving when the manager disconnects.  Runs in the poll loop; each
// topic reads its ring in a thread of its own, each port receives in one.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <utility>

#include "network.hpp"
#include "protocol.hpp"
#include "pull_messages.hpp"
#include "pull_port.hpp"
#include "pull_topic.hpp"

namespace lnd {

constexpr size_t kMaxPullTopics = 1024;             // per daemon, all instances
constexpr uint64_t kMaxPullMemory = uint64_t{256} << 20; // history bytes, all topics

class Pulls {
public:
    // `any_port`: also take port 0 (the kernel picks one; PULL_LIST shows which), for tests.
    explicit Pulls(bool any_port = false);
    ~Pulls(); // stops and joins every thread
    Pulls(const Pulls &) = delete;
    Pulls &operator=(const Pulls &) = delete;

    // True for the message types handle() takes.
    static bool handles(uint8_t type) noexcept;
    NetOutcome handle(const std::string &instance, uint8_t type, proto::Reader &r);
    // Stops every thread, closes every port (the daemon's shutdown).
    void shutdown() noexcept;

    uint64_t memory_used() const noexcept { return used_; }

private:
    using Key = std::pair<std::string, std::string>;   // instance, topic
    using PortKey = std::pair<std::string, uint16_t>; // address, port as requested
    struct Served {
        std::unique_ptr<PullTopic> topic;
        PortKey port;
    };

    NetOutcome configure(const std::string &instance, const PullTopicRequest &req);
    NetOutcome remove(const std::string &instance, const std::string &topic);
    NetOutcome status(const std::string &instance, const std::string &topic) const;
    // A reason not to take `req`, or "" with its config filled in.
    std::string check(const std::string &instance, const PullTopicRequest &req,
                      PullConfig &config) const;
    // The port for `key`, opened if needed; nullptr and the reason in `error`.
    PullPort *port_for(const PortKey &key, std::string &error);
    // Closes the port if no topic is left on it.
    void release(const PortKey &key);
    // The (instance, topic) served as `topic`, for refusals.
    std::string owner(const PullTopic *topic) const;

    const bool any_port_;
    uint64_t used_ = 0; // history bytes of every topic
    std::map<Key, Served> topics_;
    std::map<PortKey, std::unique_ptr<PullPort>> ports_;
};

} // namespace lnd
