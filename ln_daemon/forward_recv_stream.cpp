// The receiving end of a stream and the receive side's stream table
// (forward_recv_stream.hpp).
#include "forward_recv_stream.hpp"

#include <utility>

namespace lnd::fwd {

Outcome RecvStream::open(const RecvSpec &spec, const Key &daemon_key, ReassemblyBudget &budget,
                         size_t max_incomplete, std::shared_ptr<RecvStream> &out)
{
    Tap tap;
    if (Outcome o = open_tap(tap, spec.ring, spec.layout_hash, spec.message_size, LN_TAP_NEWEST);
        o.failed())
        return o;
    out = std::make_shared<RecvStream>(spec, daemon_key, std::move(tap), budget, max_incomplete);
    return outcome::ok();
}

namespace {

Key derived(const Key &daemon_key, const RecvSpec &spec)
{
    Key k;
    sec::stream_key(daemon_key, spec.token, static_cast<uint8_t>(spec.transport), k);
    return k;
}

} // namespace

RecvStream::RecvStream(const RecvSpec &spec_, const Key &daemon_key, Tap tap,
                       ReassemblyBudget &budget, size_t max_incomplete)
    : spec(spec_), key(derived(daemon_key, spec_)),
      counters(spec_.token, false, spec_.transport, spec_.transport == Transport::udp),
      reassembler(budget, max_incomplete), guard(spec_.security, key), tap_(std::move(tap))
{
    counters.note_segment(ln_ring_tap_segment(tap_.get()));
}

void RecvStream::reject(const std::string &why)
{
    StreamCounters::add(counters.rejected);
    counters.set_error(why);
}

void RecvStream::write(const uint8_t *data, uint64_t seq, int64_t timestamp_ns)
{
    std::lock_guard<std::mutex> lock(mutex_);
    if (!tap_)
        return;
    count_write(ln_ring_tap_inject(tap_.get(), data, seq, timestamp_ns));
}

void RecvStream::count_write(int rc)
{
    if (rc == LN_OK) {
        StreamCounters::add(counters.samples);
        StreamCounters::add(counters.bytes, spec.message_size);
    } else if (rc == LN_EOVERRUN) {
        StreamCounters::add(counters.stale);
    } else {
        StreamCounters::add(counters.drops);
        counters.set_error(std::string("cannot write into the ring: ") + ln_last_error());
    }
    counters.note_segment(ln_ring_tap_segment(tap_.get()));
}

bool RecvStream::begin(uint64_t seq, void **payload)
{
    mutex_.lock();
    if (tap_ && ln_ring_tap_inject_begin(tap_.get(), seq, payload) == LN_OK)
        return true; // held until finish()
    mutex_.unlock();
    return false;
}

void RecvStream::finish(bool intact, int64_t timestamp_ns, bool counted)
{
    std::lock_guard<std::mutex> lock(mutex_, std::adopt_lock);
    if (!intact) {
        ln_ring_tap_inject_abort(tap_.get());
        if (!counted)
            StreamCounters::add(counters.drops);
        return;
    }
    count_write(ln_ring_tap_inject_commit(tap_.get(), timestamp_ns));
}

uint64_t RecvStream::newest()
{
    std::lock_guard<std::mutex> lock(mutex_);
    return tap_ ? ln_ring_tap_write_seq(tap_.get()) : 0;
}

void RecvStream::close() noexcept
{
    std::lock_guard<std::mutex> lock(mutex_);
    closed_.store(true, std::memory_order_release);
    tap_.reset();
}

void RecvStream::attach(const std::string &peer)
{
    counters.set_peer(peer);
    connections_.fetch_add(1, std::memory_order_relaxed);
    counters.set_connected(true);
}

void RecvStream::detach() noexcept
{
    if (connections_.fetch_sub(1, std::memory_order_relaxed) == 1)
        counters.set_connected(false);
}

// ---- RecvTable -------------------------------------------------------------------------------

std::shared_ptr<RecvStream> RecvTable::find(uint64_t token) const
{
    std::shared_lock<std::shared_mutex> lock(mutex_);
    auto it = streams_.find(token);
    return it == streams_.end() ? nullptr : it->second;
}

std::shared_ptr<RecvStream> RecvTable::put(std::shared_ptr<RecvStream> stream)
{
    std::unique_lock<std::shared_mutex> lock(mutex_);
    std::shared_ptr<RecvStream> &slot = streams_[stream->spec.token];
    std::shared_ptr<RecvStream> old = std::move(slot);
    slot = std::move(stream);
    generation_.fetch_add(1, std::memory_order_acq_rel);
    return old;
}

std::shared_ptr<RecvStream> RecvTable::take(uint64_t token)
{
    std::unique_lock<std::shared_mutex> lock(mutex_);
    auto it = streams_.find(token);
    if (it == streams_.end())
        return nullptr;
    std::shared_ptr<RecvStream> old = std::move(it->second);
    streams_.erase(it);
    generation_.fetch_add(1, std::memory_order_acq_rel);
    return old;
}

std::vector<std::shared_ptr<RecvStream>> RecvTable::all() const
{
    std::shared_lock<std::shared_mutex> lock(mutex_);
    std::vector<std::shared_ptr<RecvStream>> out;
    out.reserve(streams_.size());
    for (const auto &entry : streams_)
        out.push_back(entry.second);
    return out;
}

} // namespace lnd::fwd
