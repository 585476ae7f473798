// The logger's sample ring (logger_buffer.hpp).  Samples are kept in publish order with
// rising sequence numbers, so a fetch finds its first sample by binary search.
#include "logger_buffer.hpp"

#include <cstring>
#include <new>

namespace lnd {

namespace {

uint64_t stride_for(uint64_t message_size) noexcept
{
    return 16 + ((message_size + 7) & ~uint64_t{7});
}

} // namespace

uint64_t SampleBuffer::bytes_for(uint32_t depth, uint64_t message_size) noexcept
{
    if (message_size > UINT64_MAX - 32)
        return UINT64_MAX;
    uint64_t out;
    if (__builtin_mul_overflow(uint64_t{depth} + 1, stride_for(message_size), &out))
        return UINT64_MAX;
    return out;
}

SampleBuffer::SampleBuffer(uint32_t depth, uint64_t message_size)
    : depth_(depth), message_size_(message_size), slots_(uint64_t{depth} + 1),
      stride_(static_cast<size_t>(stride_for(message_size))), bytes_(bytes_for(depth, message_size))
{
    if (bytes_ == UINT64_MAX || bytes_ > SIZE_MAX)
        throw std::bad_alloc();
    data_.reset(new uint8_t[static_cast<size_t>(bytes_)]);
    std::memset(data_.get(), 0, static_cast<size_t>(bytes_)); // every page mapped now
}

uint64_t SampleBuffer::seq_at(uint32_t i) const noexcept
{
    uint64_t seq;
    std::memcpy(&seq, slot(index(i)), sizeof seq);
    return seq;
}

int64_t SampleBuffer::timestamp_at(uint32_t i) const noexcept
{
    int64_t ts;
    std::memcpy(&ts, slot(index(i)) + 8, sizeof ts);
    return ts;
}

void SampleBuffer::pop_front() noexcept
{
    head_ = index(1);
    --count_;
}

uint64_t SampleBuffer::commit(uint64_t seq, int64_t timestamp_ns, int64_t span_ns) noexcept
{
    uint64_t gone = 0;
    if (count_ && seq <= last_seq()) {
        gone = count_;
        clear();
    }
    if (count_ == depth_) { // full: the oldest goes (its slot becomes the next write slot)
        pop_front();
        ++gone;
    }
    uint8_t *s = slot(tail_);
    std::memcpy(s, &seq, sizeof seq);
    std::memcpy(s + 8, &timestamp_ns, sizeof timestamp_ns);
    ++count_;
    tail_ = index(count_);
    // Older than the newest minus the span; a threshold below INT64_MIN drops nothing.
    if (span_ns > 0 && timestamp_ns >= INT64_MIN + span_ns) {
        int64_t oldest_kept = timestamp_ns - span_ns;
        while (count_ > 1 && timestamp_at(0) < oldest_kept) {
            pop_front();
            ++gone;
        }
    }
    return gone;
}

void SampleBuffer::clear() noexcept
{
    head_ = tail_;
    count_ = 0;
}

void SampleBuffer::encode_after(proto::Writer &w, uint64_t after_seq, uint32_t max_samples) const
{
    uint32_t lo = 0, hi = count_; // the first sample with seq > after_seq
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (seq_at(mid) > after_seq)
            hi = mid;
        else
            lo = mid + 1;
    }
    uint32_t n = count_ - lo < max_samples ? count_ - lo : max_samples;
    w.u32(n);
    for (uint32_t i = lo; i < lo + n; ++i) {
        w.u64(seq_at(i));
        w.i64(timestamp_at(i));
        w.raw(slot(index(i)) + kSlotHead, static_cast<size_t>(message_size_));
    }
}

} // namespace lnd
