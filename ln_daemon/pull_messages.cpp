// Codecs of the pull topic messages (pull_messages.hpp).  Every decoder ends with
// Reader::done(), so a truncated body and one with bytes left over are both refused.
#include "pull_messages.hpp"

#include <string_view>

namespace lnd {

namespace {

std::string_view cut(const std::string &s, size_t n) { return std::string_view(s).substr(0, n); }

} // namespace

bool decode_pull_topic(proto::Reader &r, PullTopicRequest &out)
{
    out.topic = r.str(proto::kMaxName);
    out.ring = r.str(proto::kMaxName);
    out.md_name = r.str(proto::kMaxName);
    out.layout_hash = r.u64();
    out.message_size = r.u64();
    out.address = r.str(proto::kMaxName);
    out.port = r.u16();
    out.name = r.str(kMaxPullName);
    out.history = r.u32();
    out.freshness_ms = r.u32();
    out.signature = r.u8();
    out.key = r.str(kMaxPullKey);
    return r.done();
}

void encode_pull_topic(proto::Writer &w, const PullTopicRequest &req)
{
    w.str(req.topic);
    w.str(req.ring);
    w.str(req.md_name);
    w.u64(req.layout_hash);
    w.u64(req.message_size);
    w.str(req.address);
    w.u16(req.port);
    w.str(req.name);
    w.u32(req.history);
    w.u32(req.freshness_ms);
    w.u8(req.signature);
    w.str(req.key);
}

bool decode_pull_topic_name(proto::Reader &r, std::string &topic)
{
    topic = r.str(proto::kMaxName);
    return r.done();
}

void encode_pull_list(proto::Writer &w, const std::vector<PullPortStatus> &ports,
                      const std::vector<PullTopicStatus> &topics)
{
    w.u32(static_cast<uint32_t>(ports.size()));
    for (const PullPortStatus &p : ports) {
        w.str(p.address);
        w.u16(p.port);
        w.u64(p.counters.packets);
        w.u64(p.counters.bad);
        w.u64(p.counters.unknown);
        w.u64(p.counters.other);
        w.str(cut(p.last_error, kMaxPullErrorText));
    }
    w.u32(static_cast<uint32_t>(topics.size()));
    for (const PullTopicStatus &t : topics) {
        w.str(t.topic);
        w.str(t.name);
        w.str(t.ring);
        w.str(t.address);
        w.u16(t.port);
        w.u32(t.history);
        w.u64(t.latest_seq);
        const PullTopicCounters &c = t.counters;
        for (uint64_t v : {c.interests, c.syncs, c.data, c.nacks, c.parked, c.expired,
                           c.duplicates, c.overflow})
            w.u64(v);
        w.str(cut(t.last_error, kMaxPullErrorText));
    }
}

bool decode_pull_list(proto::Reader &r, std::vector<PullPortStatus> &ports,
                      std::vector<PullTopicStatus> &topics)
{
    ports.clear();
    topics.clear();
    for (uint32_t i = 0, n = r.count(4 + 2 + 32 + 4); i < n && r.ok(); ++i) {
        PullPortStatus p;
        p.address = r.str();
        p.port = r.u16();
        p.counters.packets = r.u64();
        p.counters.bad = r.u64();
        p.counters.unknown = r.u64();
        p.counters.other = r.u64();
        p.last_error = r.str();
        ports.push_back(std::move(p));
    }
    for (uint32_t i = 0, n = r.count(5 * 4 + 2 + 4 + 9 * 8); i < n && r.ok(); ++i) {
        PullTopicStatus t;
        t.topic = r.str();
        t.name = r.str();
        t.ring = r.str();
        t.address = r.str();
        t.port = r.u16();
        t.history = r.u32();
        t.latest_seq = r.u64();
        PullTopicCounters &c = t.counters;
        for (uint64_t *v : {&c.interests, &c.syncs, &c.data, &c.nacks, &c.parked, &c.expired,
                            &c.duplicates, &c.overflow})
            *v = r.u64();
        t.last_error = r.str();
        topics.push_back(std::move(t));
    }
    return r.done();
}

const char *pull_msg_name(uint8_t type) noexcept
{
    switch (static_cast<proto::Msg>(type)) {
    case proto::Msg::pull_topic:
        return "PULL_TOPIC";
    case proto::Msg::pull_remove:
        return "PULL_REMOVE";
    case proto::Msg::pull_status:
        return "PULL_STATUS";
    default:
        return nullptr;
    }
}

} // namespace lnd
