// Codecs of the ring and forwarding messages (net_messages.hpp).  Every decoder ends with
// Reader::done(), so a truncated body and one with bytes left over are both refused.
#include "net_messages.hpp"

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

bool transport(proto::Reader &r, fwd::Transport &out)
{
    uint8_t v = r.u8();
    out = v == 1 ? fwd::Transport::tcp : fwd::Transport::udp;
    return v <= 1;
}

std::string_view cut(const std::string &s)
{
    return std::string_view(s).substr(0, kMaxStatText);
}

} // namespace

bool decode_ring_create(proto::Reader &r, RingCreateRequest &out)
{
    out.name = r.str(proto::kMaxName);
    out.topic = r.str(proto::kMaxName);
    out.md_name = r.str(proto::kMaxName);
    out.layout_hash = r.u64();
    out.message_size = r.u64();
    out.slots = r.u32();
    bool ok = flag(r, out.adopt);
    return ok && r.done();
}

bool decode_ring_retire(proto::Reader &r, RingRetireRequest &out)
{
    out.old_name = r.str(proto::kMaxName);
    out.successor = r.str(proto::kMaxName);
    out.timeout = r.f64();
    return r.done();
}

bool decode_ring_reader(proto::Reader &r, RingReaderRequest &out)
{
    out.name = r.str(proto::kMaxName);
    out.index = r.u32();
    out.pid = r.i32();
    out.buffers = r.u32();
    bool ok = flag(r, out.reserve);
    return ok && r.done();
}

bool decode_ring_counts(proto::Reader &r, RingCountsRequest &out)
{
    out.name = r.str(proto::kMaxName);
    out.publishers = r.u32();
    out.subscribers = r.u32();
    return r.done();
}

bool decode_ring_name(proto::Reader &r, std::string &name)
{
    name = r.str(proto::kMaxName);
    return r.done();
}

bool decode_stream_send(proto::Reader &r, fwd::SendSpec &out)
{
    out.token = r.u64();
    out.ring = r.str(proto::kMaxName);
    out.layout_hash = r.u64();
    out.message_size = r.u64();
    bool ok = transport(r, out.transport);
    out.host = r.str(proto::kMaxName);
    out.port = r.u16();
    return ok && r.done();
}

bool decode_stream_recv(proto::Reader &r, fwd::RecvSpec &out)
{
    out.token = r.u64();
    out.ring = r.str(proto::kMaxName);
    out.layout_hash = r.u64();
    out.message_size = r.u64();
    bool ok = transport(r, out.transport);
    return ok && r.done();
}

bool decode_stream_token(proto::Reader &r, uint64_t &token)
{
    token = r.u64();
    return r.done();
}

void encode_stream_list(proto::Writer &w, const fwd::Totals &totals,
                        const std::vector<fwd::StreamStats> &streams)
{
    w.u64(totals.unknown_stream);
    w.u64(totals.malformed);
    w.u32(static_cast<uint32_t>(streams.size()));
    for (const fwd::StreamStats &s : streams) {
        w.u64(s.token);
        w.u8(s.sending ? 1 : 0);
        w.u8(static_cast<uint8_t>(s.transport));
        w.str(cut(s.ring));
        w.str(cut(s.peer));
        w.u64(s.samples);
        w.u64(s.bytes);
        w.u64(s.drops);
        w.u64(s.stale);
        w.u64(s.invalid);
        w.u8(s.connected ? 1 : 0);
        w.str(cut(s.last_error));
    }
}

const char *net_msg_name(uint8_t type) noexcept
{
    switch (static_cast<proto::Msg>(type)) {
    case proto::Msg::net_info:
        return "NET_INFO";
    case proto::Msg::ring_create:
        return "RING_CREATE";
    case proto::Msg::ring_retire:
        return "RING_RETIRE";
    case proto::Msg::ring_reader:
        return "RING_READER";
    case proto::Msg::ring_counts:
        return "RING_COUNTS";
    case proto::Msg::ring_remove:
        return "RING_REMOVE";
    case proto::Msg::ring_purge:
        return "RING_PURGE";
    case proto::Msg::ring_seq:
        return "RING_SEQ";
    case proto::Msg::stream_send:
        return "STREAM_SEND";
    case proto::Msg::stream_recv:
        return "STREAM_RECV";
    case proto::Msg::stream_remove:
        return "STREAM_REMOVE";
    case proto::Msg::stream_stats:
        return "STREAM_STATS";
    default:
        return nullptr;
    }
}

} // namespace lnd
