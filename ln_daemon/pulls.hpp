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

#include "feature.hpp"
#include "outcome.hpp"
#include "protocol.hpp"
#include "pull_messages.hpp"
#include "pull_port.hpp"
#include "pull_topic.hpp"

namespace lnd {

constexpr size_t kMaxPullTopics = 1024;                  // per daemon, all instances
constexpr uint64_t kMaxPullMemory = uint64_t{256} << 20; // history bytes, all topics

class Pulls final : public Feature {
public:
    // `any_port`: also take port 0 (the kernel picks one; PULL_LIST shows which), for tests.
    explicit Pulls(bool any_port = false);
    ~Pulls() override; // stops and joins every thread
    Pulls(const Pulls &) = delete;
    Pulls &operator=(const Pulls &) = delete;

    bool handles(uint8_t type) const noexcept override;
    Outcome handle(const Request &req) override;
    // Stops every thread, closes every port.
    void shutdown() noexcept override;

    uint64_t memory_used() const noexcept { return used_; }

private:
    using Key = std::pair<std::string, std::string>;  // instance, topic
    using PortKey = std::pair<std::string, uint16_t>; // address, port as requested
    struct Served {
        std::unique_ptr<PullTopic> topic;
        PortKey port;
    };

    Outcome configure(const std::string &instance, const PullTopicRequest &req);
    Outcome remove(const std::string &instance, const std::string &topic);
    Outcome status(const std::string &instance, const std::string &topic) const;
    // Refuses `req`, or fills in its config.
    Outcome check(const std::string &instance, const PullTopicRequest &req,
                  PullConfig &config) const;
    // The port for `key` in `port`, opened if needed.
    Outcome port_for(const PortKey &key, PullPort *&port);
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
