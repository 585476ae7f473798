// The logger table (loggers.hpp): decodes each LOGGER_* request, checks it, and carries it
// out on the instance's loggers.  Every buffer is allocated here, in the poll loop, when its
// topic is configured; nothing is allocated once a logger runs.
#include "loggers.hpp"

#include <cinttypes>
#include <cmath>
#include <exception>
#include <new>
#include <vector>

#include "log.hpp"
#include "rings.hpp"
#include "spec.hpp"

namespace lnd {

using outcome::error;
using outcome::malformed;
using outcome::ok;
using outcome::reply;
using proto::Err;
using proto::Msg;

namespace {

std::string quoted(const std::string &s) { return "'" + s + "'"; }

Outcome refused(std::string text) { return error(Err::logger_failed, std::move(text)); }

std::string label(const std::string &instance, const std::string &logger, const std::string &topic)
{
    return "instance " + instance + " logger " + logger + " topic " + topic;
}

LoggerConfig config_of(const LoggerTopicRequest &req)
{
    LoggerConfig c;
    c.ring = req.ring;
    c.md_name = req.md_name;
    c.layout_hash = req.layout_hash;
    c.message_size = req.message_size;
    c.depth = req.depth;
    c.divisor = req.divisor;
    c.span_s = req.span_s;
    return c;
}

} // namespace

Loggers::Loggers(uint64_t memory_limit) : limit_(memory_limit) {}

Loggers::~Loggers() { shutdown(); }

bool Loggers::handles(uint8_t type) const noexcept { return logger_msg_name(type) != nullptr; }

Outcome Loggers::handle(const Request &req)
{
    return outcome::guarded(req.instance, Err::logger_failed, [&]() -> Outcome {
        using outcome::decoded;
        const auto &in = req.instance;
        proto::Reader &r = req.body;
        switch (static_cast<Msg>(req.type)) {
        case Msg::logger_topic:
            return decoded<LoggerTopicRequest>(r, decode_logger_topic,
                                               [&](auto &q) { return configure(in, q); });
        case Msg::logger_remove:
            return decoded<LoggerRemoveRequest>(r, decode_logger_remove,
                                                [&](auto &q) { return remove(in, q); });
        case Msg::logger_enable:
            return decoded<LoggerEnableRequest>(r, decode_logger_enable,
                                                [&](auto &q) { return enable(in, q); });
        case Msg::logger_fetch:
            return decoded<LoggerFetchRequest>(r, decode_logger_fetch,
                                               [&](auto &q) { return fetch(in, q); });
        case Msg::logger_status:
            return decoded<std::string>(r, decode_logger_status,
                                        [&](auto &q) { return status(in, q); });
        default:
            return malformed(); // not reached: handles() admits only the types above
        }
    });
}

void Loggers::shutdown() noexcept
{
    size_t running = 0;
    for (auto &entry : loggers_)
        for (auto &topic : entry.second.topics)
            if (topic.second->running()) {
                topic.second->request_stop();
                ++running;
            }
    for (auto &entry : loggers_)
        for (auto &topic : entry.second.topics)
            topic.second->join();
    if (running)
        logf("stopped %zu logger thread(s)", running);
}

Outcome Loggers::find(const std::string &instance, const std::string &logger, Logger *&found)
{
    auto it = loggers_.find({instance, logger});
    if (it == loggers_.end())
        return refused("no logger " + quoted(logger) + " in instance " + instance);
    found = &it->second;
    return ok();
}

Outcome Loggers::check(const std::string &instance, const LoggerTopicRequest &req) const
{
    if (limit_ == 0)
        return refused("topic logging is disabled on this daemon (it was started with "
                       "--logger-memory 0)");
    if (!valid_name(req.logger))
        return refused("invalid logger name " + quoted(req.logger) +
                       " (1-255 bytes, no control characters)");
    if (!valid_name(req.topic))
        return refused("invalid topic name " + quoted(req.topic) + " for logger " +
                       quoted(req.logger) + " (1-255 bytes, no control characters)");
    std::string what = "logger " + quoted(req.logger) + " topic " + quoted(req.topic) + ": ";
    if (Outcome o = ring_in_namespace(instance, req.ring, Err::logger_failed); o.failed())
        return outcome::prefixed(what, std::move(o));
    if (req.message_size < 1 || req.message_size > kMaxLoggedMessage)
        return refused(what + "message size " + std::to_string(req.message_size) +
                       " out of range 1.." + std::to_string(kMaxLoggedMessage) +
                       " (one sample has to fit a LOGGER_DATA reply)");
    if (req.depth < 1)
        return refused(what + "depth must be at least 1");
    if (req.divisor < 1)
        return refused(what + "divisor must be at least 1");
    if (!std::isfinite(req.span_s) || req.span_s < 0 || req.span_s > kMaxLoggerSpan)
        return refused(what + "span must be 0 (none) or a number of seconds up to 1e9");
    return ok();
}

Outcome Loggers::configure(const std::string &instance, const LoggerTopicRequest &req)
{
    if (Outcome o = check(instance, req); o.failed())
        return o;
    LoggerConfig config = config_of(req);
    auto found = loggers_.find({instance, req.logger});
    LoggerTopic *old = nullptr;
    if (found != loggers_.end()) {
        auto t = found->second.topics.find(req.topic);
        if (t != found->second.topics.end())
            old = t->second.get();
    }
    if (old && old->same_geometry(config)) {
        bool moved = old->config().ring != config.ring;
        old->update(config);
        logf("%s: %s (depth %u, divisor %u, span %g s)",
             label(instance, req.logger, req.topic).c_str(),
             moved ? ("now on ring " + config.ring).c_str() : "updated", config.depth,
             config.divisor, config.span_s);
        return ok();
    }
    if (!old && topics_ >= kMaxLoggerTopics)
        return error(Err::limit, "too many logger topics (" + std::to_string(kMaxLoggerTopics) +
                                     ") on this daemon");
    uint64_t needed = SampleBuffer::bytes_for(config.depth, config.message_size);
    uint64_t used_by_others = used_ - (old ? old->memory() : 0);
    uint64_t free = limit_ - used_by_others;
    if (needed > free)
        return error(Err::logger_failed,
                     "logger " + quoted(req.logger) + " topic " + quoted(req.topic) + " needs " +
                         std::to_string(needed) + " bytes (depth " + std::to_string(config.depth) +
                         " of " + std::to_string(config.message_size) +
                         "-byte samples), but only " + std::to_string(free) +
                         " of the daemon's logger memory limit of " + std::to_string(limit_) +
                         " bytes are free; raise the limit with ln_daemon --logger-memory");
    std::unique_ptr<LoggerTopic> fresh;
    try {
        fresh = std::make_unique<LoggerTopic>(config, label(instance, req.logger, req.topic));
    } catch (const std::bad_alloc &) {
        return error(Err::logger_failed, "logger " + quoted(req.logger) + " topic " +
                                             quoted(req.topic) + ": cannot allocate " +
                                             std::to_string(needed) + " bytes");
    }
    Logger &logger = loggers_[{instance, req.logger}];
    if (old) { // reallocated: the old data goes
        old->request_stop();
        old->join();
        used_ -= old->memory();
        --topics_;
    }
    LoggerTopic &topic = *fresh;
    logger.topics[req.topic] = std::move(fresh);
    used_ += needed;
    ++topics_;
    logf("%s: %s on ring %s (depth %u of %" PRIu64 " bytes, divisor %u, span %g s, %" PRIu64
         " bytes; %" PRIu64 " of %" PRIu64 " in use)",
         label(instance, req.logger, req.topic).c_str(), old ? "reallocated" : "configured",
         config.ring.c_str(), config.depth, config.message_size, config.divisor, config.span_s,
         needed, used_, limit_);
    if (logger.enabled)
        topic.start();
    return ok();
}

Outcome Loggers::remove(const std::string &instance, const LoggerRemoveRequest &req)
{
    Logger *logger = nullptr;
    if (Outcome o = find(instance, req.logger, logger); o.failed())
        return o;
    std::vector<std::string> names;
    if (req.topic.empty()) {
        for (auto &t : logger->topics)
            names.push_back(t.first);
    } else if (logger->topics.count(req.topic)) {
        names.push_back(req.topic);
    } else {
        return error(Err::logger_failed,
                     "logger " + quoted(req.logger) + " has no topic " + quoted(req.topic));
    }
    for (const std::string &name : names)
        logger->topics[name]->request_stop();
    for (const std::string &name : names) {
        auto it = logger->topics.find(name);
        used_ -= it->second->memory();
        --topics_;
        logger->topics.erase(it); // joins
        logf("%s: removed", label(instance, req.logger, name).c_str());
    }
    if (logger->topics.empty())
        loggers_.erase({instance, req.logger});
    return ok();
}

Outcome Loggers::enable(const std::string &instance, const LoggerEnableRequest &req)
{
    Logger *logger = nullptr;
    if (Outcome o = find(instance, req.logger, logger); o.failed())
        return o;
    if (!req.enable) {
        for (auto &t : logger->topics)
            t.second->request_stop();
        for (auto &t : logger->topics)
            t.second->join();
    }
    if (req.clear)
        for (auto &t : logger->topics)
            t.second->clear();
    logger->enabled = req.enable;
    if (req.enable)
        for (auto &t : logger->topics)
            t.second->start();
    logf("instance %s logger %s: %s%s", instance.c_str(), req.logger.c_str(),
         req.enable ? "enabled" : "disabled", req.clear ? ", cleared" : "");
    return ok();
}

Outcome Loggers::fetch(const std::string &instance, const LoggerFetchRequest &req)
{
    Logger *logger = nullptr;
    if (Outcome o = find(instance, req.logger, logger); o.failed())
        return o;
    auto it = logger->topics.find(req.topic);
    if (it == logger->topics.end())
        return error(Err::logger_failed,
                     "logger " + quoted(req.logger) + " has no topic " + quoted(req.topic));
    proto::Writer w;
    it->second->fetch(w, req.after_seq, req.max_bytes);
    return reply(Msg::logger_data, std::move(w.buffer()));
}

Outcome Loggers::status(const std::string &instance, const std::string &name)
{
    std::vector<LoggerTopicStatus> list;
    auto add = [&](const std::string &logger_name, const Logger &logger) {
        for (const auto &t : logger.topics) {
            LoggerTopicStatus s = t.second->status();
            s.logger = logger_name;
            s.topic = t.first;
            list.push_back(std::move(s));
        }
    };
    if (name.empty()) {
        for (auto it = loggers_.lower_bound({instance, ""});
             it != loggers_.end() && it->first.first == instance; ++it)
            add(it->first.second, it->second);
    } else {
        Logger *logger = nullptr;
        if (Outcome o = find(instance, name, logger); o.failed())
            return o;
        add(name, *logger);
    }
    proto::Writer w;
    encode_logger_list(w, limit_, used_, list);
    return reply(Msg::logger_list, std::move(w.buffer()));
}

} // namespace lnd
