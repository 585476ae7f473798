// Reassembly of fragmented UDP samples (forward_reassembly.hpp).  A sample's buffer is
// allocated when its first fragment arrives (uninitialised: every byte gets written by
// exactly one fragment before the sample counts as complete) and charged to the budget
// together with its fragment bitmap.
#include "forward_reassembly.hpp"

#include <cstring>
#include <new>

namespace lnd::fwd {

// ---- ReassemblyBudget ------------------------------------------------------------------------

bool ReassemblyBudget::take(size_t bytes) noexcept
{
    size_t used = used_.load(std::memory_order_relaxed);
    do {
        if (bytes > limit_ || used > limit_ - bytes)
            return false;
    } while (!used_.compare_exchange_weak(used, used + bytes, std::memory_order_relaxed));
    size_t now = used + bytes, peak = peak_.load(std::memory_order_relaxed);
    while (now > peak && !peak_.compare_exchange_weak(peak, now, std::memory_order_relaxed)) {
    }
    return true;
}

void ReassemblyBudget::give(size_t bytes) noexcept
{
    used_.fetch_sub(bytes, std::memory_order_relaxed);
}

// ---- Reassembler -----------------------------------------------------------------------------

Reassembler::Reassembler(ReassemblyBudget &budget, size_t max_incomplete) noexcept
    : budget_(budget), max_incomplete_(max_incomplete)
{}

Reassembler::~Reassembler()
{
    for (const Entry &e : entries_)
        budget_.give(e.charged);
}

Reassembler::Entry *Reassembler::find(uint64_t seq) noexcept
{
    for (Entry &e : entries_)
        if (e.seq == seq)
            return &e;
    return nullptr;
}

bool Reassembler::active(uint64_t seq) const noexcept
{
    for (const Entry &e : entries_)
        if (e.seq == seq)
            return true;
    return false;
}

void Reassembler::remember(uint64_t seq) noexcept
{
    recent_[recent_next_] = seq;
    recent_next_ = (recent_next_ + 1) % kRecent;
}

bool Reassembler::recently_done(uint64_t seq) const noexcept
{
    for (uint64_t done : recent_)
        if (done == seq)
            return true;
    return false;
}

void Reassembler::drop(size_t index) noexcept
{
    Entry &e = entries_[index];
    budget_.give(e.charged);
    remember(e.seq);
    if (index + 1 != entries_.size())
        e = std::move(entries_.back());
    entries_.pop_back();
}

uint64_t Reassembler::drop_older_than(uint64_t seq) noexcept
{
    uint64_t n = 0;
    for (size_t i = entries_.size(); i-- > 0;) {
        if (entries_[i].seq < seq) {
            drop(i);
            ++n;
        }
    }
    return n;
}

Reassembler::Outcome Reassembler::store(Entry &e, const wire::Fragment &f, int64_t now_ns)
{
    Outcome out;
    uint64_t &word = e.have[f.index / 64];
    uint64_t bit = uint64_t(1) << (f.index % 64);
    if (word & bit) {
        out.kind = Outcome::ignored;
        return out;
    }
    word |= bit;
    if (f.length)
        std::memcpy(e.data.get() + static_cast<uint64_t>(f.index) * e.chunk, f.data, f.length);
    e.last_ns = now_ns;
    if (++e.received == e.count) {
        out.kind = Outcome::complete;
        out.data = e.data.get();
    }
    return out;
}

Reassembler::Outcome Reassembler::add(const wire::Fragment &f, uint64_t ring_newest, int64_t now_ns)
{
    Outcome out;
    if (Entry *e = find(f.seq)) {
        if (e->size != f.sample_size || e->chunk != f.chunk_size ||
            e->timestamp_ns != f.timestamp_ns) {
            out.kind = Outcome::mismatch;
            return out;
        }
        return store(*e, f, now_ns);
    }
    if (recently_done(f.seq)) {
        out.kind = Outcome::ignored;
        return out;
    }
    if (f.seq <= ring_newest) {
        remember(f.seq);
        out.kind = Outcome::stale;
        return out;
    }
    // Room in the table: the oldest sample in progress makes way, unless this one is older.
    if (max_incomplete_ == 0 || entries_.size() >= max_incomplete_) {
        size_t oldest = 0;
        for (size_t i = 1; i < entries_.size(); ++i)
            if (entries_[i].seq < entries_[oldest].seq)
                oldest = i;
        if (entries_.empty() || f.seq < entries_[oldest].seq) {
            remember(f.seq);
            out.kind = Outcome::too_old;
            out.given_up = 1;
            return out;
        }
        drop(oldest);
        ++out.given_up;
    }
    // Room in the budget: older samples of this stream make way.
    uint64_t words = (static_cast<uint64_t>(f.count) + 63) / 64;
    size_t charge = static_cast<size_t>(f.sample_size + words * sizeof(uint64_t));
    while (!budget_.take(charge)) {
        size_t oldest = entries_.size();
        for (size_t i = 0; i < entries_.size(); ++i)
            if (entries_[i].seq < f.seq &&
                (oldest == entries_.size() || entries_[i].seq < entries_[oldest].seq))
                oldest = i;
        if (oldest == entries_.size()) {
            remember(f.seq);
            out.kind = Outcome::no_memory;
            ++out.given_up;
            return out;
        }
        drop(oldest);
        ++out.given_up;
    }
    Entry e;
    e.data.reset(new (std::nothrow) uint8_t[f.sample_size ? f.sample_size : 1]);
    if (!e.data) {
        budget_.give(charge);
        remember(f.seq);
        out.kind = Outcome::no_memory;
        ++out.given_up;
        return out;
    }
    e.have.assign(words, 0);
    e.seq = f.seq;
    e.timestamp_ns = f.timestamp_ns;
    e.size = f.sample_size;
    e.chunk = f.chunk_size;
    e.count = f.count;
    e.charged = charge;
    entries_.push_back(std::move(e));
    Outcome stored = store(entries_.back(), f, now_ns);
    stored.given_up = out.given_up;
    return stored;
}

uint64_t Reassembler::finish(uint64_t seq)
{
    for (size_t i = 0; i < entries_.size(); ++i) {
        if (entries_[i].seq == seq) {
            drop(i);
            break;
        }
    }
    return drop_older_than(seq);
}

uint64_t Reassembler::supersede(uint64_t seq) { return drop_older_than(seq); }

uint64_t Reassembler::expire(int64_t now_ns, int64_t max_idle_ns)
{
    uint64_t n = 0;
    for (size_t i = entries_.size(); i-- > 0;) {
        if (now_ns - entries_[i].last_ns > max_idle_ns) {
            drop(i);
            ++n;
        }
    }
    return n;
}

} // namespace lnd::fwd
