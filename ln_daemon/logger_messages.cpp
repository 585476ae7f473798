// The topic logging messages (logger_messages.hpp) through the generated codec.
#include "logger_messages.hpp"

#include <algorithm>

namespace lnd {

bool decode_logger_topic(proto::Reader &r, LoggerTopicRequest &out) { return wire::decode(r, out); }

bool decode_logger_remove(proto::Reader &r, LoggerRemoveRequest &out)
{
    return wire::decode(r, out);
}

bool decode_logger_enable(proto::Reader &r, LoggerEnableRequest &out)
{
    return wire::decode(r, out);
}

bool decode_logger_fetch(proto::Reader &r, LoggerFetchRequest &out) { return wire::decode(r, out); }

bool decode_logger_status(proto::Reader &r, std::string &logger)
{
    wire::LoggerStatus req;
    bool ok = wire::decode(r, req);
    logger = std::move(req.logger);
    return ok;
}

void encode_logger_data_head(proto::Writer &w, const LoggerDataHead &head)
{
    if (head.md_name.size() <= proto::kMaxName && head.samples.empty())
        return wire::encode(w, head);
    LoggerDataHead cut = head;
    cut.md_name.resize(std::min(cut.md_name.size(), proto::kMaxName));
    cut.samples.clear(); // the caller appends them
    wire::encode(w, cut);
}

void encode_logger_list(proto::Writer &w, uint64_t memory_limit, uint64_t memory_used,
                        const std::vector<LoggerTopicStatus> &topics)
{
    wire::LoggerList list{memory_limit, memory_used, topics};
    for (LoggerTopicStatus &t : list.topics)
        t.last_error.resize(std::min(t.last_error.size(), kMaxLoggerErrorText));
    wire::encode(w, list);
}

const char *logger_msg_name(uint8_t type) noexcept
{
    switch (static_cast<proto::Msg>(type)) {
    case proto::Msg::logger_topic:
    case proto::Msg::logger_remove:
    case proto::Msg::logger_enable:
    case proto::Msg::logger_fetch:
    case proto::Msg::logger_status:
        return wire::name(static_cast<proto::Msg>(type));
    default:
        return nullptr;
    }
}

} // namespace lnd
