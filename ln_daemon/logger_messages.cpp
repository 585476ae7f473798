// Codecs of the topic logging messages (logger_messages.hpp).  Every decoder ends with
// Reader::done(), so a truncated body and one with bytes left over are both refused.
#include "logger_messages.hpp"

#include <string_view>

namespace lnd {

namespace {

// A u8 that must be 0 or 1.
bool flag(proto::Reader &r, bool &out)
{
    uint8_t v = r.u8();
    out = v == 1;
    return v <= 1;
}

void counters(proto::Writer &w, const LoggerCounters &c)
{
    w.u64(c.received);
    w.u64(c.stored);
    w.u64(c.missed);
    w.u64(c.skipped);
    w.u64(c.dropped);
}

} // namespace

bool decode_logger_topic(proto::Reader &r, LoggerTopicRequest &out)
{
    out.logger = r.str(proto::kMaxName);
    out.topic = r.str(proto::kMaxName);
    out.ring = r.str(proto::kMaxName);
    out.md_name = r.str(proto::kMaxName);
    out.layout_hash = r.u64();
    out.message_size = r.u64();
    out.depth = r.u32();
    out.divisor = r.u32();
    out.span_s = r.f64();
    return r.done();
}

bool decode_logger_remove(proto::Reader &r, LoggerRemoveRequest &out)
{
    out.logger = r.str(proto::kMaxName);
    out.topic = r.str(proto::kMaxName);
    return r.done();
}

bool decode_logger_enable(proto::Reader &r, LoggerEnableRequest &out)
{
    out.logger = r.str(proto::kMaxName);
    bool ok = flag(r, out.enable);
    ok = flag(r, out.clear) && ok;
    return ok && r.done();
}

bool decode_logger_fetch(proto::Reader &r, LoggerFetchRequest &out)
{
    out.logger = r.str(proto::kMaxName);
    out.topic = r.str(proto::kMaxName);
    out.after_seq = r.u64();
    out.max_bytes = r.u32();
    return r.done();
}

bool decode_logger_status(proto::Reader &r, std::string &logger)
{
    logger = r.str(proto::kMaxName);
    return r.done();
}

void encode_logger_data_head(proto::Writer &w, const LoggerDataHead &head)
{
    w.u64(head.message_size);
    w.u64(head.layout_hash);
    w.str(std::string_view(head.md_name).substr(0, proto::kMaxName));
    w.u8(head.enabled ? 1 : 0);
    counters(w, head.counters);
    w.u64(head.first_seq);
    w.u64(head.last_seq);
    w.u64(head.start_seq);
}

void encode_logger_list(proto::Writer &w, uint64_t memory_limit, uint64_t memory_used,
                        const std::vector<LoggerTopicStatus> &topics)
{
    w.u64(memory_limit);
    w.u64(memory_used);
    w.u32(static_cast<uint32_t>(topics.size()));
    for (const LoggerTopicStatus &t : topics) {
        w.str(t.logger);
        w.str(t.topic);
        w.str(t.ring);
        w.str(t.md_name);
        w.u8(t.enabled ? 1 : 0);
        w.u32(t.depth);
        w.u32(t.divisor);
        w.f64(t.span_s);
        w.u64(t.message_size);
        counters(w, t.counters);
        w.str(std::string_view(t.last_error).substr(0, kMaxLoggerErrorText));
    }
}

const char *logger_msg_name(uint8_t type) noexcept
{
    switch (static_cast<proto::Msg>(type)) {
    case proto::Msg::logger_topic:
        return "LOGGER_TOPIC";
    case proto::Msg::logger_remove:
        return "LOGGER_REMOVE";
    case proto::Msg::logger_enable:
        return "LOGGER_ENABLE";
    case proto::Msg::logger_fetch:
        return "LOGGER_FETCH";
    case proto::Msg::logger_status:
        return "LOGGER_STATUS";
    default:
        return nullptr;
    }
}

} // namespace lnd
