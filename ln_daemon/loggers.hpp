// The daemon's topic loggers (docs/daemon.md, "Topic logging"): the LOGGER_* requests,
// the table of loggers by (instance, logger name) with their topics, and the memory limit
// (--logger-memory) every buffer of the daemon shares, checked when a topic is configured,
// never later.  Loggers belong to their instance, not to a connection: they keep running and
// keep their samples when the manager disconnects.  Runs in the poll loop; each enabled
// topic reads its ring in a thread of its own.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <utility>

#include "logger_messages.hpp"
#include "logger_topic.hpp"
#include "feature.hpp"
#include "outcome.hpp"
#include "protocol.hpp"

namespace lnd {

constexpr uint64_t kDefaultLoggerMemory = uint64_t{256} << 20;
constexpr size_t kMaxLoggerTopics = 2048; // per daemon, all instances (LOGGER_LIST fits a frame)
constexpr double kMaxLoggerSpan = 1e9;    // seconds

class Loggers final : public Feature {
public:
    // `memory_limit` bytes for every buffer together; 0 disables topic logging.
    explicit Loggers(uint64_t memory_limit);
    ~Loggers() override; // stops and joins every thread
    Loggers(const Loggers &) = delete;
    Loggers &operator=(const Loggers &) = delete;

    bool handles(uint8_t type) const noexcept override;
    Outcome handle(const Request &req) override;
    // Stops every logger thread and waits for them.
    void shutdown() noexcept override;

    uint64_t memory_used() const noexcept { return used_; }

private:
    struct Logger {
        bool enabled = false;
        std::map<std::string, std::unique_ptr<LoggerTopic>> topics; // by topic name
    };
    using Key = std::pair<std::string, std::string>; // instance, logger name

    Outcome configure(const std::string &instance, const LoggerTopicRequest &req);
    Outcome remove(const std::string &instance, const LoggerRemoveRequest &req);
    Outcome enable(const std::string &instance, const LoggerEnableRequest &req);
    Outcome fetch(const std::string &instance, const LoggerFetchRequest &req);
    Outcome status(const std::string &instance, const std::string &logger);
    // The logger in `found`, or refused.
    Outcome find(const std::string &instance, const std::string &logger, Logger *&found);
    // Refuses `req`, or ok.
    Outcome check(const std::string &instance, const LoggerTopicRequest &req) const;

    const uint64_t limit_;
    uint64_t used_ = 0; // bytes of every buffer
    size_t topics_ = 0; // logger topics of every instance
    std::map<Key, Logger> loggers_;
};

} // namespace lnd
