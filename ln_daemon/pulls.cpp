// The pull topic table (pulls.hpp): decodes each PULL_* request, checks it, and carries it
// out.  Histories and ports are made here, in the poll loop, when a topic is configured;
// nothing is allocated once a topic serves.  A refused request leaves everything as it was.
#include "pulls.hpp"

#include <cinttypes>
#include <algorithm>
#include <exception>
#include <new>
#include <vector>

#include "log.hpp"
#include "pull_messages.hpp"
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

std::string label(const std::string &instance, const std::string &topic)
{
    return "instance " + instance + " pull topic " + topic;
}

Outcome refused(std::string text) { return error(Err::pull_failed, std::move(text)); }

std::string where(const std::string &address, uint16_t port)
{
    return (address.empty() ? "0.0.0.0" : address) + ":" + std::to_string(port);
}

} // namespace

Pulls::Pulls(bool any_port) : any_port_(any_port) {}

Pulls::~Pulls() { shutdown(); }

bool Pulls::handles(uint8_t type) const noexcept { return pull_msg_name(type) != nullptr; }

Outcome Pulls::handle(const Request &req)
{
    return outcome::guarded(req.instance, Err::pull_failed, [&]() -> Outcome {
        using outcome::decoded;
        const auto &in = req.instance;
        proto::Reader &r = req.body;
        switch (static_cast<Msg>(req.type)) {
        case Msg::pull_topic:
            return decoded<PullTopicRequest>(r, decode_pull_topic,
                                             [&](auto &q) { return configure(in, q); });
        case Msg::pull_remove:
            return decoded<std::string>(r, decode_pull_topic_name,
                                        [&](auto &q) { return remove(in, q); });
        case Msg::pull_status:
            return decoded<std::string>(r, decode_pull_topic_name,
                                        [&](auto &q) { return status(in, q); });
        default:
            return malformed(); // not reached: handles() admits only the types above
        }
    });
}

void Pulls::shutdown() noexcept
{
    for (auto &entry : topics_)
        entry.second.topic->request_stop();
    for (auto &entry : topics_)
        entry.second.topic->join();
    size_t n = topics_.size();
    topics_.clear();
    ports_.clear(); // joins the receive threads
    used_ = 0;
    if (n)
        logf("stopped %zu pull topic(s)", n);
}

Outcome Pulls::check(const std::string &instance, const PullTopicRequest &req,
                     PullConfig &config) const
{
    if (!valid_name(req.topic))
        return refused("invalid topic name " + quoted(req.topic) +
                       " (1-255 bytes, no control characters)");
    const std::string what = "pull topic " + quoted(req.topic) + ": ";
    if (Outcome o = ring_in_namespace(instance, req.ring, Err::pull_failed); o.failed())
        return outcome::prefixed(what, std::move(o));
    if (req.message_size < 1 || req.message_size > kMaxPullMessage)
        return refused(what + "message size " + std::to_string(req.message_size) +
                       " out of range 1.." + std::to_string(kMaxPullMessage) +
                       " (a sample travels in one UDP datagram; pull topics do not segment)");
    if (req.port == 0 && !any_port_)
        return refused(what + "port 0 is not a port to serve on");
    if (req.history < 1 || req.history > kMaxPullHistory)
        return refused(what + "history " + std::to_string(req.history) + " out of range 1.." +
                       std::to_string(kMaxPullHistory));
    if (req.signature == LN_NDN_SIG_DIGEST_SHA256 && !req.key.empty())
        return refused(what +
                       "a key is given, but the signature is DigestSha256 (0); HMAC-SHA256 is 4");
    if (req.signature == LN_NDN_SIG_HMAC_SHA256 && req.key.empty())
        return refused(what + "HMAC-SHA256 needs a key");
    if (req.signature != LN_NDN_SIG_DIGEST_SHA256 && req.signature != LN_NDN_SIG_HMAC_SHA256)
        return refused(what + "unknown signature type " + std::to_string(req.signature) +
                       " (0 DigestSha256, 4 HMAC-SHA256)");
    std::vector<uint8_t> name(req.name.size() * 2 + 64);
    int n = ln_ndn_name_from_uri(name.data(), name.size(), req.name.c_str());
    if (n < 0 || req.name.find('\0') != std::string::npos)
        return refused(what + "name " + quoted(req.name) + " is not a valid NDN URI (" +
                       (n < 0 ? ln_ndn_strerror(n) : "a NUL byte") + ")");
    if (n == 0)
        return refused(what + "name " + quoted(req.name) + " has no component");
    name.resize(static_cast<size_t>(n));
    config.ring = req.ring;
    config.md_name = req.md_name;
    config.layout_hash = req.layout_hash;
    config.message_size = req.message_size;
    config.uri = req.name;
    config.name = std::move(name);
    config.history = req.history;
    config.freshness_ms = req.freshness_ms;
    config.signature = req.signature;
    config.key = req.key;
    return ok();
}

Outcome Pulls::port_for(const PortKey &key, PullPort *&port)
{
    auto it = ports_.find(key);
    if (it != ports_.end()) {
        port = it->second.get();
        return ok();
    }
    std::unique_ptr<PullPort> opened;
    if (Outcome o = PullPort::open(key.first, key.second, opened); o.failed())
        return o;
    logf("pull port %s:%u open", opened->address().c_str(), opened->port());
    port = opened.get();
    ports_[key] = std::move(opened);
    return ok();
}

void Pulls::release(const PortKey &key)
{
    auto it = ports_.find(key);
    if (it == ports_.end() || it->second->topics() > 0)
        return;
    logf("pull port %s:%u closed (no topic left)", it->second->address().c_str(),
         it->second->port());
    ports_.erase(it); // joins its thread
}

std::string Pulls::owner(const PullTopic *topic) const
{
    for (const auto &entry : topics_)
        if (entry.second.topic.get() == topic)
            return "topic " + quoted(entry.first.second) + " of instance " + entry.first.first;
    return "another topic";
}

Outcome Pulls::configure(const std::string &instance, const PullTopicRequest &req)
{
    PullConfig config;
    if (Outcome o = check(instance, req, config); o.failed())
        return o;
    const std::string what = "pull topic " + quoted(req.topic) + ": ";
    const PortKey key{req.address.empty() ? "0.0.0.0" : req.address, req.port};
    auto found = topics_.find({instance, req.topic});
    Served *old = found != topics_.end() ? &found->second : nullptr;
    if (!old && topics_.size() >= kMaxPullTopics)
        return error(Err::limit, "too many pull topics (" + std::to_string(kMaxPullTopics) +
                                     ") on this daemon");
    const bool keep = old && old->topic->same_geometry(config);
    const uint64_t needed = PullTopic::bytes_for(config.history, config.message_size);
    const uint64_t free = kMaxPullMemory - (used_ - (old ? old->topic->memory() : 0));
    if (needed > free)
        return error(Err::pull_failed, what + "a history of " + std::to_string(config.history) +
                                           " samples of " + std::to_string(config.message_size) +
                                           " bytes needs " + std::to_string(needed) +
                                           " bytes, but only " + std::to_string(free) +
                                           " of the daemon's " + std::to_string(kMaxPullMemory) +
                                           " bytes for pull histories are free");
    PullPort *port = nullptr;
    if (Outcome o = port_for(key, port); o.failed())
        return outcome::prefixed(what, std::move(o));
    if (const PullTopic *other = port->serving(config.name, old ? old->topic.get() : nullptr)) {
        std::string text = what + "name " + quoted(req.name) + " is served already on " +
                           where(key.first, port->port()) + " by " + owner(other);
        release(key);
        return error(Err::pull_failed, text);
    }
    std::unique_ptr<PullTopic> fresh;
    if (!keep) {
        try {
            fresh = std::make_unique<PullTopic>(config, label(instance, req.topic));
        } catch (const std::bad_alloc &) {
            release(key);
            return error(Err::pull_failed,
                         what + "cannot allocate " + std::to_string(needed) + " bytes");
        }
    }
    // From here on nothing is refused: the old topic stops, the new one serves.
    PortKey old_port;
    if (old) {
        old->topic->request_stop();
        old->topic->join();
        if (PullPort *p = ports_.count(old->port) ? ports_[old->port].get() : nullptr)
            p->detach(old->topic.get());
        used_ -= old->topic->memory();
        old_port = old->port;
    }
    Served &entry = topics_[{instance, req.topic}];
    if (keep)
        entry.topic->reconfigure(config);
    else
        entry.topic = std::move(fresh);
    entry.port = key;
    used_ += needed;
    port->attach(entry.topic.get());
    entry.topic->start(port->fd());
    if (old && old_port != key)
        release(old_port);
    logf("%s: %s %s on %s from ring %s (history %u of %" PRIu64 " bytes, freshness %u ms, %s)",
         label(instance, req.topic).c_str(),
         !old   ? "serving"
         : keep ? "updated, serving"
                : "reallocated, serving",
         req.name.c_str(), where(key.first, port->port()).c_str(), config.ring.c_str(),
         config.history, config.message_size, config.freshness_ms,
         config.signature == LN_NDN_SIG_HMAC_SHA256 ? "HMAC-SHA256" : "DigestSha256");
    return ok();
}

Outcome Pulls::remove(const std::string &instance, const std::string &topic)
{
    std::vector<std::map<Key, Served>::iterator> gone;
    if (topic.empty()) {
        for (auto it = topics_.lower_bound({instance, ""});
             it != topics_.end() && it->first.first == instance; ++it)
            gone.push_back(it);
    } else {
        auto it = topics_.find({instance, topic});
        if (it == topics_.end())
            return error(Err::pull_failed,
                         "no pull topic " + quoted(topic) + " in instance " + instance);
        gone.push_back(it);
    }
    for (auto it : gone)
        it->second.topic->request_stop();
    for (auto it : gone) {
        Served &s = it->second;
        s.topic->join();
        ports_[s.port]->detach(s.topic.get());
        used_ -= s.topic->memory();
        PortKey port = s.port;
        logf("%s: removed", label(instance, it->first.second).c_str());
        topics_.erase(it);
        release(port);
    }
    return ok();
}

Outcome Pulls::status(const std::string &instance, const std::string &topic) const
{
    std::vector<PullTopicStatus> list;
    std::vector<PortKey> keys;
    auto add = [&](const std::string &name, const Served &s) {
        const PullPort &port = *ports_.at(s.port);
        PullTopicStatus t = s.topic->status();
        t.topic = name;
        t.address = port.address();
        t.port = port.port();
        list.push_back(std::move(t));
        if (std::find(keys.begin(), keys.end(), s.port) == keys.end())
            keys.push_back(s.port);
    };
    if (topic.empty()) {
        for (auto it = topics_.lower_bound({instance, ""});
             it != topics_.end() && it->first.first == instance; ++it)
            add(it->first.second, it->second);
    } else {
        auto it = topics_.find({instance, topic});
        if (it == topics_.end())
            return error(Err::pull_failed,
                         "no pull topic " + quoted(topic) + " in instance " + instance);
        add(topic, it->second);
    }
    std::sort(keys.begin(), keys.end());
    std::vector<PullPortStatus> ports;
    for (const PortKey &k : keys)
        ports.push_back(ports_.at(k)->status());
    proto::Writer w;
    encode_pull_list(w, ports, list);
    return reply(Msg::pull_list, std::move(w.buffer()));
}

} // namespace lnd
