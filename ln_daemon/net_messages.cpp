// The ring and forwarding messages (net_messages.hpp) through the generated codec; what is
// here converts between its structs and the forwarder's.
#include "net_messages.hpp"

namespace lnd {

namespace {

fwd::Transport transport(wire::Transport t)
{
    return t == wire::Transport::tcp ? fwd::Transport::tcp : fwd::Transport::udp;
}

fwd::Level level(wire::Security s)
{
    switch (s) {
    case wire::Security::none:
        return fwd::Level::none;
    case wire::Security::encrypt:
        return fwd::Level::encrypt;
    default:
        return fwd::Level::authenticate;
    }
}

std::string cut(const std::string &s) { return s.substr(0, kMaxStatText); }

// The fields STREAM_SEND and STREAM_RECV share.
template <class Request, class Spec>
void stream_fields(Request &req, Spec &out)
{
    out.token = req.token;
    out.ring = std::move(req.ring);
    out.layout_hash = req.layout_hash;
    out.message_size = req.message_size;
    out.transport = transport(req.transport);
    out.security = level(req.security);
}

} // namespace

bool decode_ring_create(proto::Reader &r, RingCreateRequest &out) { return wire::decode(r, out); }
bool decode_ring_retire(proto::Reader &r, RingRetireRequest &out) { return wire::decode(r, out); }
bool decode_ring_reader(proto::Reader &r, RingReaderRequest &out) { return wire::decode(r, out); }
bool decode_ring_counts(proto::Reader &r, RingCountsRequest &out) { return wire::decode(r, out); }

bool decode_ring_name(proto::Reader &r, std::string &name)
{
    wire::RingRemove req; // the same layout as RING_SEQ
    bool ok = wire::decode(r, req);
    name = std::move(req.name);
    return ok;
}

bool decode_stream_send(proto::Reader &r, fwd::SendSpec &out)
{
    wire::StreamSend req;
    if (!wire::decode(r, req))
        return false;
    stream_fields(req, out);
    out.host = std::move(req.host);
    out.port = req.port;
    return true;
}

bool decode_stream_recv(proto::Reader &r, fwd::RecvSpec &out)
{
    wire::StreamRecv req;
    if (!wire::decode(r, req))
        return false;
    stream_fields(req, out);
    return true;
}

bool decode_stream_token(proto::Reader &r, uint64_t &token)
{
    wire::StreamRemove req;
    bool ok = wire::decode(r, req);
    token = req.token;
    return ok;
}

void encode_stream_list(proto::Writer &w, const fwd::Totals &totals,
                        const std::vector<fwd::StreamStats> &streams)
{
    wire::StreamList list;
    list.unknown_stream = totals.unknown_stream;
    list.malformed = totals.malformed;
    list.streams.reserve(streams.size());
    for (const fwd::StreamStats &s : streams) {
        wire::StreamStat &o = list.streams.emplace_back();
        o.token = s.token;
        o.sending = s.sending;
        o.transport =
            s.transport == fwd::Transport::tcp ? wire::Transport::tcp : wire::Transport::udp;
        o.ring = cut(s.ring);
        o.peer = cut(s.peer);
        o.samples = s.samples;
        o.bytes = s.bytes;
        o.drops = s.drops;
        o.stale = s.stale;
        o.invalid = s.invalid;
        o.rejected = s.rejected;
        o.connected = s.connected;
        o.last_error = cut(s.last_error);
    }
    wire::encode(w, list);
}

const char *net_msg_name(uint8_t type) noexcept
{
    switch (static_cast<proto::Msg>(type)) {
    case proto::Msg::net_info:
    case proto::Msg::ring_create:
    case proto::Msg::ring_retire:
    case proto::Msg::ring_reader:
    case proto::Msg::ring_counts:
    case proto::Msg::ring_remove:
    case proto::Msg::ring_purge:
    case proto::Msg::ring_seq:
    case proto::Msg::stream_send:
    case proto::Msg::stream_recv:
    case proto::Msg::stream_remove:
    case proto::Msg::stream_stats:
        return wire::name(static_cast<proto::Msg>(type));
    default:
        return nullptr;
    }
}

} // namespace lnd
