// StreamCounters: what one stream's threads count and report, readable at any time by
// stats() from another thread.  Numbers are relaxed atomics (each has one writer thread);
// the strings sit behind a mutex that the data path takes only when a string changes.
#pragma once

#include <atomic>
#include <cstdint>
#include <mutex>
#include <string>

#include "forward.hpp"

namespace lnd::fwd {

class StreamCounters {
public:
    StreamCounters(uint64_t token, bool sending, Transport transport, bool connected)
        : token_(token), sending_(sending), transport_(transport), connected_(connected)
    {}

    std::atomic<uint64_t> samples{0};
    std::atomic<uint64_t> bytes{0};
    std::atomic<uint64_t> drops{0};
    std::atomic<uint64_t> stale{0};
    std::atomic<uint64_t> invalid{0};
    std::atomic<uint64_t> rejected{0};

    static void add(std::atomic<uint64_t> &counter, uint64_t n = 1) noexcept
    {
        counter.fetch_add(n, std::memory_order_relaxed);
    }

    // Release/acquire with snapshot(): an error set before a change of state is seen with it.
    void set_connected(bool up) noexcept { connected_.store(up, std::memory_order_release); }
    void set_error(const std::string &text)
    {
        std::lock_guard<std::mutex> lock(mutex_);
        last_error_ = text;
    }
    void set_peer(const std::string &text)
    {
        std::lock_guard<std::mutex> lock(mutex_);
        peer_ = text;
    }
    // Called, under whatever serializes the use of the tap, after reads and writes: copies the
    // segment name only when it changed (the tap followed a successor).
    void note_segment(const char *name)
    {
        if (segment_cache_ == name)
            return;
        segment_cache_ = name;
        std::lock_guard<std::mutex> lock(mutex_);
        ring_ = name;
    }

    StreamStats snapshot() const
    {
        StreamStats s;
        s.token = token_;
        s.sending = sending_;
        s.transport = transport_;
        s.samples = samples.load(std::memory_order_relaxed);
        s.bytes = bytes.load(std::memory_order_relaxed);
        s.drops = drops.load(std::memory_order_relaxed);
        s.stale = stale.load(std::memory_order_relaxed);
        s.invalid = invalid.load(std::memory_order_relaxed);
        s.rejected = rejected.load(std::memory_order_relaxed);
        s.connected = connected_.load(std::memory_order_acquire);
        std::lock_guard<std::mutex> lock(mutex_);
        s.ring = ring_;
        s.peer = peer_;
        s.last_error = last_error_;
        return s;
    }

private:
    const uint64_t token_;
    const bool sending_;
    const Transport transport_;
    std::atomic<bool> connected_;
    mutable std::mutex mutex_;
    std::string ring_, peer_, last_error_;
    std::string segment_cache_; // owner thread only: what ring_ was last set to
};

} // namespace lnd::fwd
