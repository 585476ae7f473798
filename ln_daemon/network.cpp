// NetCommands (network.hpp): decodes each ring and stream request, checks that the instance
// may touch what it names, carries it out through the RingTable or the Forwarder and says
// what to answer.  Streams are tagged with their instance, so one instance can neither see
// nor stop another's.
#include "network.hpp"

#include <cinttypes>
#include <cstdio>
#include <utility>

#include "log.hpp"
#include "net_messages.hpp"

namespace lnd {

using proto::Err;
using proto::Msg;

using outcome::error;
using outcome::malformed;
using outcome::ok;
using outcome::reply;

namespace {

Outcome value(uint64_t v)
{
    proto::Writer w;
    w.u64(v);
    return reply(Msg::value, w.buffer());
}

std::string token_text(uint64_t token)
{
    char buf[32];
    std::snprintf(buf, sizeof buf, "%016" PRIx64, token);
    return buf;
}

} // namespace

NetCommands::NetCommands(std::string host_id, uint16_t data_port, fwd::Forwarder &forwarder)
    : host_id_(std::move(host_id)), data_port_(data_port), forwarder_(forwarder)
{}

bool NetCommands::handles(uint8_t type) const noexcept { return net_msg_name(type) != nullptr; }

Outcome NetCommands::handle(const Request &req)
{
    const std::string &instance = req.instance;
    proto::Reader &r = req.body;
    switch (static_cast<Msg>(req.type)) {
    case Msg::net_info: {
        if (!r.done())
            return malformed();
        proto::Writer w;
        w.str(host_id_);
        w.u16(data_port_);
        return reply(Msg::net_details, w.buffer());
    }
    case Msg::ring_purge:
        if (!r.done())
            return malformed();
        return purge(instance);
    case Msg::stream_send:
    case Msg::stream_recv:
    case Msg::stream_remove:
    case Msg::stream_stats:
        return streams(instance, req.type, r);
    default:
        return rings(instance, req.type, r);
    }
}

Outcome NetCommands::rings(const std::string &instance, uint8_t type, proto::Reader &r)
{
    switch (static_cast<Msg>(type)) {
    case Msg::ring_create: {
        RingCreateRequest req;
        if (!decode_ring_create(r, req))
            return malformed();
        if (Outcome o = rings_.create(instance, req); o.failed()) {
            logf("instance %s: %s", instance.c_str(), o.text.c_str());
            return o;
        }
        logf("instance %s: ring %s %s (%u slots of %" PRIu64 " bytes, topic %s)", instance.c_str(),
             req.name.c_str(), req.adopt ? "adopted" : "created", req.slots, req.message_size,
             req.topic.c_str());
        return ok();
    }
    case Msg::ring_retire: {
        RingRetireRequest req;
        if (!decode_ring_retire(r, req))
            return malformed();
        if (Outcome o = rings_.retire(instance, req); o.failed())
            return o;
        logf("instance %s: ring %s retired into %s", instance.c_str(), req.old_name.c_str(),
             req.successor.c_str());
        return ok();
    }
    case Msg::ring_reader: {
        RingReaderRequest req;
        if (!decode_ring_reader(r, req))
            return malformed();
        return rings_.reader(instance, req);
    }
    case Msg::ring_counts: {
        RingCountsRequest req;
        if (!decode_ring_counts(r, req))
            return malformed();
        return rings_.counts(instance, req);
    }
    case Msg::ring_remove: {
        std::string name;
        if (!decode_ring_name(r, name))
            return malformed();
        if (Outcome o = rings_.remove(instance, name); o.failed())
            return o;
        logf("instance %s: ring %s removed", instance.c_str(), name.c_str());
        return ok();
    }
    case Msg::ring_seq: {
        std::string name;
        if (!decode_ring_name(r, name))
            return malformed();
        uint64_t seq = 0;
        Outcome o = rings_.write_seq(instance, name, seq);
        return o.failed() ? o : value(seq);
    }
    default:
        return malformed(); // not reached: handles() admits only the types above
    }
}

Outcome NetCommands::streams(const std::string &instance, uint8_t type, proto::Reader &r)
{
    switch (static_cast<Msg>(type)) {
    case Msg::stream_send: {
        fwd::SendSpec spec;
        if (!decode_stream_send(r, spec))
            return malformed();
        if (Outcome o = admit(instance, spec.token, spec.ring); o.failed())
            return o;
        std::string to = spec.host + ":" + std::to_string(spec.port);
        return added(instance, spec.token, spec.ring, ("sending to " + to).c_str(),
                     forwarder_.set_send(spec));
    }
    case Msg::stream_recv: {
        fwd::RecvSpec spec;
        if (!decode_stream_recv(r, spec))
            return malformed();
        if (Outcome o = admit(instance, spec.token, spec.ring); o.failed())
            return o;
        return added(instance, spec.token, spec.ring, "receiving", forwarder_.set_recv(spec));
    }
    case Msg::stream_remove: {
        uint64_t token = 0;
        if (!decode_stream_token(r, token))
            return malformed();
        auto it = streams_.find(token);
        if (it == streams_.end() || it->second != instance)
            return error(Err::unknown_stream,
                         "no stream " + token_text(token) + " in instance " + instance);
        streams_.erase(it);
        forwarder_.remove(token);
        logf("instance %s: stream %s removed", instance.c_str(), token_text(token).c_str());
        return ok();
    }
    case Msg::stream_stats: {
        if (!r.done())
            return malformed();
        std::vector<fwd::StreamStats> mine;
        for (fwd::StreamStats &s : forwarder_.stats()) {
            auto it = streams_.find(s.token);
            if (it != streams_.end() && it->second == instance)
                mine.push_back(std::move(s));
        }
        proto::Writer w;
        encode_stream_list(w, forwarder_.totals(), mine);
        return reply(Msg::stream_list, w.buffer());
    }
    default:
        return malformed(); // not reached
    }
}

Outcome NetCommands::admit(const std::string &instance, uint64_t token,
                           const std::string &ring) const
{
    if (Outcome o = ring_in_namespace(instance, ring, Err::stream_failed); o.failed())
        return o;
    auto it = streams_.find(token);
    if (it != streams_.end() && it->second != instance)
        return error(Err::stream_failed,
                     "stream token " + token_text(token) + " is in use by another instance");
    if (it == streams_.end() && streams_.size() >= kMaxStreams)
        return error(Err::limit,
                     "too many streams (" + std::to_string(kMaxStreams) + ") on this daemon");
    return ok();
}

Outcome NetCommands::added(const std::string &instance, uint64_t token, const std::string &ring,
                           const char *what, Outcome verdict)
{
    if (verdict.failed()) {
        logf("instance %s: stream %s on %s not started: %s", instance.c_str(),
             token_text(token).c_str(), ring.c_str(), verdict.text.c_str());
        return verdict;
    }
    streams_[token] = instance;
    logf("instance %s: stream %s on %s %s", instance.c_str(), token_text(token).c_str(),
         ring.c_str(), what);
    return ok();
}

Outcome NetCommands::purge(const std::string &instance)
{
    size_t stopped = 0;
    for (auto it = streams_.begin(); it != streams_.end();) {
        if (it->second == instance) {
            forwarder_.remove(it->first);
            it = streams_.erase(it);
            ++stopped;
        } else {
            ++it;
        }
    }
    uint64_t count = 0;
    if (Outcome o = rings_.purge(instance, count); o.failed())
        return o;
    logf("instance %s: purged %" PRIu64 " segment(s), stopped %zu stream(s)", instance.c_str(),
         count, stopped);
    return value(count);
}

} // namespace lnd
