// SampleBuffer: the preallocated in-memory ring of one logger topic.  depth + 1 slots of
// seq, timestamp and the message, allocated and touched at construction: the extra slot is
// the one the logger's thread reads the next sample into (outside any lock), so committing
// a sample never copies it again.  Not thread-safe: the LoggerTopic serializes every call
// but write_slot(), whose slot no other call touches.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>

#include "protocol.hpp"

namespace lnd {

class SampleBuffer {
public:
    // Bytes a buffer of `depth` samples of `message_size` takes ((depth + 1) slots of 16
    // bytes plus the message rounded up to 8); UINT64_MAX if that overflows.
    static uint64_t bytes_for(uint32_t depth, uint64_t message_size) noexcept;

    // Allocates and touches every byte; throws std::bad_alloc.
    SampleBuffer(uint32_t depth, uint64_t message_size);
    SampleBuffer(const SampleBuffer &) = delete;
    SampleBuffer &operator=(const SampleBuffer &) = delete;

    uint32_t depth() const noexcept { return depth_; }
    uint64_t message_size() const noexcept { return message_size_; }
    uint64_t bytes() const noexcept { return bytes_; }

    // Where the next sample's message goes; stays the same until commit().
    uint8_t *write_slot() noexcept { return slot(tail_) + kSlotHead; }

    // Makes the write slot the newest sample, then evicts the oldest beyond the depth and,
    // with span_ns > 0, those older than timestamp_ns - span_ns (never the new one).  A seq
    // not above the newest stored one (the topic's numbering started afresh) first empties
    // the buffer, so sequence numbers always rise.  Returns how many samples left.
    uint64_t commit(uint64_t seq, int64_t timestamp_ns, int64_t span_ns) noexcept;
    // Empties the buffer (the write slot stays where it is).
    void clear() noexcept;

    uint32_t size() const noexcept { return count_; }
    uint64_t first_seq() const noexcept { return count_ ? seq_at(0) : 0; }
    uint64_t last_seq() const noexcept { return count_ ? seq_at(count_ - 1) : 0; }

    // Appends u32 n and n samples (u64 seq, i64 timestamp, message) with seq > after_seq,
    // oldest first: as many as there are, at most max_samples.
    void encode_after(proto::Writer &w, uint64_t after_seq, uint32_t max_samples) const;

private:
    static constexpr size_t kSlotHead = 16; // u64 seq, i64 timestamp_ns

    uint8_t *slot(uint32_t physical) const noexcept
    {
        return data_.get() + static_cast<size_t>(physical) * stride_;
    }
    // Physical index of the i-th oldest sample.
    uint32_t index(uint32_t i) const noexcept
    {
        uint64_t p = uint64_t{head_} + i;
        return static_cast<uint32_t>(p >= slots_ ? p - slots_ : p);
    }
    uint64_t seq_at(uint32_t i) const noexcept;
    int64_t timestamp_at(uint32_t i) const noexcept;
    void pop_front() noexcept;

    const uint32_t depth_;
    const uint64_t message_size_;
    const uint64_t slots_; // depth + 1
    const size_t stride_;  // bytes per slot
    const uint64_t bytes_;
    std::unique_ptr<uint8_t[]> data_;
    uint32_t head_ = 0;  // physical index of the oldest sample
    uint32_t count_ = 0; // samples stored
    uint32_t tail_ = 0;  // physical index of the write slot: head_ + count_ (mod slots_)
};

} // namespace lnd
