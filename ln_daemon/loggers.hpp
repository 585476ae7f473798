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
#include "network.hpp"
#include "protocol.hpp"

namespace lnd {

constexpr uint64_t kDefaultLoggerMemory = uint64_t{256} << 20;
constexpr size_t kMaxLoggerTopics = 2048;   // per daemon, all instances (LOGGER_LIST fits a frame)
constexpr double kMaxLoggerSpan = 1e9;      // seconds

class Loggers {
public:
    // `memory_limit` bytes for every buffer together; 0 disables topic logging.
    explicit Loggers(uint64_t memory_limit);
    ~Loggers(); // stops and joins every thread
    Loggers(const Loggers &) = delete;
    Loggers &operator=(const Loggers &) = delete;

    // True for the message types handle() takes.
    static bool handles(uint8_t type) noexcept;
    NetOutcome handle(const std::string &instance, uint8_t type, proto::Reader &r);
    // Stops every logger thread and waits for them (the daemon's shutdown).
    void shutdown() noexcept;

    uint64_t memory_used() const noexcept { return used_; }

private:
    struct Logger {
        bool enabled = false;
        std::map<std::string, std::unique_ptr<LoggerTopic>> topics; // by topic name
    };
    using Key = std::pair<std::string, std::string>; // instance, logger name

    NetOutcome configure(const std::string &instance, const LoggerTopicRequest &req);
    NetOutcome remove(const std::string &instance, const LoggerRemoveRequest &req);
    NetOutcome enable(const std::string &instance, const LoggerEnableRequest &req);
    NetOutcome fetch(const std::string &instance, const LoggerFetchRequest &req);
    NetOutcome status(const std::string &instance, const std::string &logger);
    // The logger, or nullptr with the refusal in `error`.
    Logger *find(const std::string &instance, const std::string &logger, NetOutcome &error);
    // A reason not to take `req`, or "".
    std::string check(const std::string &instance, const LoggerTopicRequest &req) const;

    const uint64_t limit_;
    uint64_t used_ = 0;   // bytes of every buffer
    size_t topics_ = 0;   // logger topics of every instance
    std::map<Key, Logger> loggers_;
};

} // namespace lnd
