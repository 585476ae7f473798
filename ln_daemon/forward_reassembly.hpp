// Reassembly of fragmented UDP samples: per stream a few samples in progress, all streams
// together within one memory budget.  Newest sample wins: a newer sample pushes out the
// oldest incomplete one, a completed sample makes every older incomplete one pointless.
// Used only by the UDP receive thread, so nothing here locks (the budget is atomic because
// streams may be destroyed on other threads).
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "forward_wire.hpp"

namespace lnd::fwd {

class ReassemblyBudget {
public:
    explicit ReassemblyBudget(size_t limit) noexcept : limit_(limit) {}
    bool take(size_t bytes) noexcept; // false (nothing taken) if it would exceed the limit
    void give(size_t bytes) noexcept;
    size_t used() const noexcept { return used_.load(std::memory_order_relaxed); }
    size_t peak() const noexcept { return peak_.load(std::memory_order_relaxed); }
    size_t limit() const noexcept { return limit_; }

private:
    const size_t limit_;
    std::atomic<size_t> used_{0};
    std::atomic<size_t> peak_{0};
};

class Reassembler {
public:
    Reassembler(ReassemblyBudget &budget, size_t max_incomplete) noexcept;
    ~Reassembler();
    Reassembler(const Reassembler &) = delete;
    Reassembler &operator=(const Reassembler &) = delete;

    struct Outcome {
        enum Kind {
            pending,   // stored; the sample is not complete yet
            complete,  // `data` holds the whole sample until finish(seq)
            ignored,   // a duplicate fragment, or one of a sample already dealt with
            stale,     // first fragment of a sample not newer than the ring's newest
            mismatch,  // disagrees with earlier fragments of its sample (size, chunk, time)
            too_old,   // not started: older than every sample in progress, and no room
            no_memory, // not started: the memory budget (or the allocator) does not allow it
        } kind = pending;
        uint64_t given_up = 0; // incomplete samples abandoned by this call (incl. itself)
        const uint8_t *data = nullptr;
    };

    // Adds a fragment that passed wire::check_fragment for this stream.  `ring_newest` is the
    // ring's newest sequence number, `now_ns` a monotonic time for expiry.
    Outcome add(const wire::Fragment &f, uint64_t ring_newest, int64_t now_ns);
    // After a `complete` outcome was dealt with: frees it and gives up every older sample in
    // progress (they can no longer be written).  Returns how many were given up.
    uint64_t finish(uint64_t seq);
    // A single-fragment sample `seq` went straight into the ring: gives up older ones.
    uint64_t supersede(uint64_t seq);
    // Gives up samples that received no fragment for `max_idle_ns`.
    uint64_t expire(int64_t now_ns, int64_t max_idle_ns);
    size_t in_progress() const noexcept { return entries_.size(); }
    // True if sample `seq` is being reassembled (its fragments need no look at the ring).
    bool active(uint64_t seq) const noexcept;

private:
    struct Entry {
        uint64_t seq = 0;
        int64_t timestamp_ns = 0;
        uint64_t size = 0;
        uint16_t chunk = 0;
        uint32_t count = 0;
        uint32_t received = 0;
        size_t charged = 0; // bytes taken from the budget
        int64_t last_ns = 0;
        std::unique_ptr<uint8_t[]> data;
        std::vector<uint64_t> have; // one bit per fragment
    };

    Entry *find(uint64_t seq) noexcept;
    void drop(size_t index) noexcept; // frees entry `index`, remembers its seq
    uint64_t drop_older_than(uint64_t seq) noexcept;
    void remember(uint64_t seq) noexcept;
    bool recently_done(uint64_t seq) const noexcept;
    Outcome store(Entry &e, const wire::Fragment &f, int64_t now_ns);

    ReassemblyBudget &budget_;
    const size_t max_incomplete_;
    std::vector<Entry> entries_;
    // Samples completed, stale or given up lately: their late fragments are ignored rather
    // than starting them again.
    static constexpr size_t kRecent = 64;
    uint64_t recent_[kRecent] = {};
    size_t recent_next_ = 0;
};

} // namespace lnd::fwd
