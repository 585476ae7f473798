// Forwarder (forward.hpp): the data sockets, the table of sending and receiving streams,
// and the order in which their threads start and stop.  Changes of the table are
// serialized by one mutex held across stopping and joining the old threads; stats() and
// the receive threads only take the tables' own short locks, so they never wait for that.
#include "forward.hpp"

#include <algorithm>
#include <cerrno>
#include <exception>
#include <map>
#include <mutex>
#include <system_error>
#include <utility>

#include "forward_net.hpp"
#include "forward_reassembly.hpp"
#include "forward_recv_stream.hpp"
#include "forward_send_stream.hpp"
#include "forward_tcp_recv.hpp"
#include "forward_tcp_send.hpp"
#include "forward_udp_recv.hpp"
#include "forward_udp_send.hpp"
#include "forward_wire.hpp"

namespace lnd::fwd {

namespace {

const Options &checked(const Options &o)
{
    auto invalid = [](const std::string &what) {
        throw std::system_error(EINVAL, std::generic_category(), "forwarder options: " + what);
    };
    if (o.udp_payload == 0 || o.udp_payload > wire::kMaxChunk)
        invalid("udp_payload must be 1.." + std::to_string(wire::kMaxChunk));
    if (o.udp_max_incomplete == 0)
        invalid("udp_max_incomplete must be at least 1");
    if (o.tcp_queue_samples == 0 || o.tcp_queue_bytes == 0)
        invalid("the TCP queue bounds must be at least 1");
    if (!(o.udp_incomplete_timeout > 0))
        invalid("udp_incomplete_timeout must be positive");
    if (!(o.udp_max_rate >= 0) || o.udp_max_rate > 1e15)
        invalid("udp_max_rate must be 0 (no limit) or a rate in bytes per second");
    return o;
}

Outcome refused(std::string text)
{
    return outcome::error(proto::Err::stream_failed, std::move(text));
}

Outcome check_common(uint64_t token, const std::string &ring, uint64_t message_size)
{
    if (token == 0)
        return refused("stream token 0 is not allowed");
    if (ring.empty())
        return refused("no ring named");
    if (message_size == 0)
        return refused("message size 0");
    return outcome::ok();
}

Outcome not_started(const std::exception &e)
{
    return refused(std::string("cannot start the stream: ") + e.what());
}

} // namespace

struct Forwarder::Impl {
    explicit Impl(const Options &o)
        : options(checked(o)), key(o.key),
          sockets(bind_data_sockets(o.bind_address, o.data_port, o.socket_buffer)),
          budget(o.udp_reassembly_bytes), udp(sockets.udp.get(), receivers, totals, options),
          tcp(sockets.tcp.get(), receivers, totals, options.spin_us)
    {
        udp.start();
        try {
            tcp.start();
        } catch (...) {
            udp.stop();
            throw;
        }
    }

    ~Impl()
    {
        udp.stop();
        tcp.stop();
        std::lock_guard<std::mutex> lock(control);
        std::map<uint64_t, std::unique_ptr<SendStream>> all;
        {
            std::lock_guard<std::mutex> table_lock(senders_mutex);
            all.swap(senders);
        }
        for (auto &entry : all) // stop all first, so their waits end together
            entry.second->stop();
        for (auto &entry : all)
            entry.second->join();
        for (const auto &stream : receivers.all())
            stream->close();
    }

    std::unique_ptr<SendStream> take_sender(uint64_t token)
    {
        std::lock_guard<std::mutex> lock(senders_mutex);
        auto it = senders.find(token);
        if (it == senders.end())
            return nullptr;
        std::unique_ptr<SendStream> old = std::move(it->second);
        senders.erase(it);
        return old;
    }

    // After a receiving stream left the table: nothing more reaches its ring.
    void retire(const std::shared_ptr<RecvStream> &old)
    {
        old->close();
        if (old->spec.transport == Transport::tcp)
            tcp.drop_stream(old->spec.token);
    }

    // The options with the current key (set_key()).
    Options current() const
    {
        Options o = options;
        std::lock_guard<std::mutex> lock(key_mutex);
        o.key = key;
        return o;
    }

    const Options options;
    mutable std::mutex key_mutex;
    Key key; // options.key until set_key()
    DataSockets sockets;
    ReassemblyBudget budget; // before the streams, whose reassemblers give memory back
    TotalCounters totals;
    RecvTable receivers;
    std::mutex control; // one set_send/set_recv/remove at a time
    std::mutex senders_mutex;
    std::map<uint64_t, std::unique_ptr<SendStream>> senders;
    UdpReceiver udp;
    TcpReceiver tcp;
};

Forwarder::Forwarder(const Options &options) : impl_(std::make_unique<Impl>(options)) {}

Forwarder::~Forwarder() = default;

uint16_t Forwarder::data_port() const { return impl_->sockets.port; }

Outcome Forwarder::set_send(const SendSpec &spec)
{
    if (Outcome o = check_common(spec.token, spec.ring, spec.message_size); o.failed())
        return o;
    if (spec.host.empty())
        return refused("no receiving host named");
    if (spec.port == 0)
        return refused("no receiving port named");
    try {
        std::unique_ptr<SendStream> stream;
        const Options options = impl_->current();
        Outcome created = spec.transport == Transport::tcp
                              ? TcpSender::create(spec, options, stream)
                              : UdpSender::create(spec, options, stream);
        if (created.failed())
            return created;
        std::lock_guard<std::mutex> lock(impl_->control);
        if (std::unique_ptr<SendStream> old = impl_->take_sender(spec.token)) {
            old->stop();
            old->join();
        }
        stream->start();
        std::lock_guard<std::mutex> table_lock(impl_->senders_mutex);
        impl_->senders[spec.token] = std::move(stream);
        return outcome::ok();
    } catch (const std::exception &e) {
        return not_started(e);
    }
}

Outcome Forwarder::set_recv(const RecvSpec &spec)
{
    if (Outcome o = check_common(spec.token, spec.ring, spec.message_size); o.failed())
        return o;
    try {
        std::shared_ptr<RecvStream> stream;
        if (Outcome o = RecvStream::open(spec, impl_->current().key, impl_->budget,
                                         impl_->options.udp_max_incomplete, stream);
            o.failed())
            return o;
        std::lock_guard<std::mutex> lock(impl_->control);
        if (std::shared_ptr<RecvStream> old = impl_->receivers.put(std::move(stream)))
            impl_->retire(old);
        return outcome::ok();
    } catch (const std::exception &e) {
        return not_started(e);
    }
}

bool Forwarder::remove(uint64_t token)
{
    std::lock_guard<std::mutex> lock(impl_->control);
    bool found = false;
    if (std::unique_ptr<SendStream> old = impl_->take_sender(token)) {
        old->stop();
        old->join();
        found = true;
    }
    if (std::shared_ptr<RecvStream> old = impl_->receivers.take(token)) {
        impl_->retire(old);
        found = true;
    }
    return found;
}

std::vector<StreamStats> Forwarder::stats() const
{
    std::vector<StreamStats> out;
    {
        std::lock_guard<std::mutex> lock(impl_->senders_mutex);
        for (const auto &entry : impl_->senders)
            out.push_back(entry.second->stats());
    }
    for (const auto &stream : impl_->receivers.all())
        out.push_back(stream->counters.snapshot());
    std::stable_sort(out.begin(), out.end(),
                     [](const StreamStats &a, const StreamStats &b) { return a.token < b.token; });
    return out;
}

Outcome Forwarder::set_key(const Key &key)
{
    {
        std::lock_guard<std::mutex> lock(impl_->key_mutex);
        impl_->key = key;
    }
    // Each stream again from its spec: new stream keys, salts and connections.  The daemon
    // calls this from its poll loop, the thread that also adds and removes streams.
    std::vector<SendSpec> sending;
    {
        std::lock_guard<std::mutex> lock(impl_->senders_mutex);
        for (const auto &entry : impl_->senders)
            sending.push_back(entry.second->spec());
    }
    Outcome result = outcome::ok();
    auto keep_first = [&result](Outcome o) {
        if (o.failed() && !result.failed())
            result = std::move(o);
    };
    for (const auto &stream : impl_->receivers.all())
        keep_first(set_recv(stream->spec));
    for (const SendSpec &spec : sending)
        keep_first(set_send(spec));
    return result;
}

Totals Forwarder::totals() const
{
    Totals t;
    t.unknown_stream = impl_->totals.unknown_stream.load(std::memory_order_relaxed);
    t.malformed = impl_->totals.malformed.load(std::memory_order_relaxed);
    t.reassembly_bytes = impl_->budget.used();
    t.reassembly_peak = impl_->budget.peak();
    return t;
}

} // namespace lnd::fwd
