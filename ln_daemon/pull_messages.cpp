// The pull topic messages (pull_messages.hpp) through the generated codec.
#include "pull_messages.hpp"

#include <algorithm>

namespace lnd {

bool decode_pull_topic(proto::Reader &r, PullTopicRequest &out) { return wire::decode(r, out); }

void encode_pull_topic(proto::Writer &w, const PullTopicRequest &req) { wire::encode(w, req); }

bool decode_pull_topic_name(proto::Reader &r, std::string &topic)
{
    wire::PullRemove req; // the same layout as PULL_STATUS
    bool ok = wire::decode(r, req);
    topic = std::move(req.topic);
    return ok;
}

void encode_pull_list(proto::Writer &w, const std::vector<PullPortStatus> &ports,
                      const std::vector<PullTopicStatus> &topics)
{
    wire::PullList list{ports, topics};
    for (PullPortStatus &p : list.ports)
        p.last_error.resize(std::min(p.last_error.size(), kMaxPullErrorText));
    for (PullTopicStatus &t : list.topics)
        t.last_error.resize(std::min(t.last_error.size(), kMaxPullErrorText));
    wire::encode(w, list);
}

bool decode_pull_list(proto::Reader &r, std::vector<PullPortStatus> &ports,
                      std::vector<PullTopicStatus> &topics)
{
    wire::PullList list;
    bool ok = wire::decode(r, list);
    ports = std::move(list.ports);
    topics = std::move(list.topics);
    return ok;
}

const char *pull_msg_name(uint8_t type) noexcept
{
    switch (static_cast<proto::Msg>(type)) {
    case proto::Msg::pull_topic:
    case proto::Msg::pull_remove:
    case proto::Msg::pull_status:
        return wire::name(static_cast<proto::Msg>(type));
    default:
        return nullptr;
    }
}

} // namespace lnd
