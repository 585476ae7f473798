// LoggerTopic: one topic of one logger (docs/daemon.md, "Topic logging").  While enabled, a
// thread of its own reads the topic's ring through an LN_TAP_EVERY tap (which holds no
// reader slot, so the publisher never waits for it) into a preallocated SampleBuffer, keeping
// the samples whose seq is a multiple of the divisor and counting everything else.  The poll
// loop configures, starts, stops, clears and reads it; the buffer and the counters sit behind
// a mutex that either side holds only briefly.
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include <ln/ln.h>

#include "forward_net.hpp"
#include "forward_tap.hpp"
#include "logger_buffer.hpp"
#include "logger_messages.hpp"
#include "outcome.hpp"
#include "protocol.hpp"

namespace lnd {

struct LoggerConfig {
    std::string ring; // shm name of the topic's ring on this host
    std::string md_name;
    uint64_t layout_hash = 0;
    uint64_t message_size = 0;
    uint32_t depth = 1;
    uint32_t divisor = 1;
    double span_s = 0;
};

// How the reading thread waits (logger_topic.cpp).  A topic of up to about kLoggerPollAbove
// samples/s is waited for on the ring's futex: each publish wakes the thread (the publisher
// makes a system call then, as for any subscriber that sleeps), which keeps the logger
// closest to the publisher.  A faster topic is polled at an interval in which at most a
// quarter of the ring fills, so the publisher makes no system call for the logger at all;
// below kLoggerWaitBelow it is waited for on the futex again.
constexpr double kLoggerPollAbove = 2000; // samples/s
constexpr double kLoggerWaitBelow = 1000;
constexpr int64_t kLoggerMinPollUs = 100;
constexpr int64_t kLoggerMaxPollUs = 5000;
// A publisher that fills the ring four times over within kLoggerMinPollUs outruns any
// logger: looking more often would catch a few more samples but contend with the publisher
// for the slots it writes.  The logger then looks this often.
constexpr int64_t kLoggerSaturatedPollUs = 1000;
constexpr int64_t kLoggerRetryUs = 500000; // between attempts to open (or reopen) the ring

class LoggerTopic {
public:
    // Allocates and touches the buffer (std::bad_alloc).  `label` names it in the daemon's
    // log ("instance I logger L topic T").
    LoggerTopic(const LoggerConfig &config, std::string label);
    ~LoggerTopic(); // stops and joins the thread
    LoggerTopic(const LoggerTopic &) = delete;
    LoggerTopic &operator=(const LoggerTopic &) = delete;

    const LoggerConfig &config() const noexcept { return config_; }
    uint64_t memory() const noexcept { return buffer_.bytes(); }
    // Same buffer shape and layout: update() can take the config without losing data.
    bool same_geometry(const LoggerConfig &c) const noexcept;
    // Takes md_name, divisor, span and ring of a config of the same geometry.  A new ring
    // while running: the thread moves to it (unless its tap followed the ring there
    // already), keeping the data and counting samples it did not see in between as missed.
    void update(const LoggerConfig &c);

    // Starts reading with a fresh tap (samples published from now on), unless running.  The
    // tap is opened here, so the first sample published after the call is logged; if the
    // ring cannot be opened the reason goes to last_error and the thread retries every
    // kLoggerRetryUs.  Throws std::system_error if no thread can be made.
    void start();
    // Stopping is two steps, so that stopping many topics waits for them in parallel.
    void request_stop() noexcept;
    void join() noexcept;
    bool running() const noexcept { return run_ != nullptr; }

    // Empties the buffer and zeroes the counters.
    void clear();
    LoggerTopicStatus status() const; // logger and topic left empty
    // The LOGGER_DATA payload: samples with seq > after_seq whose wire bytes (16 + message
    // size each) fit max_bytes, at least one if any, never more than one frame holds.
    void fetch(proto::Writer &w, uint64_t after_seq, uint32_t max_bytes) const;

private:
    struct Run {
        fwd::StopSignal stop;
        std::thread thread;
    };

    void start_run(bool keep_baseline);
    // A tap was opened: a fresh capture (nothing seen since enable) starts at its newest seq.
    void began(ln_ring_tap *tap);
    void loop(Run &run, fwd::Tap tap);
    // Opens a tap on `ring`; "" or why not.
    Outcome open_tap(fwd::Tap &tap, const std::string &ring) const;
    // The tap's segment, noted when it changed (it follows successors); its slot count.
    uint32_t note_segment(ln_ring_tap *tap, std::string &seen);
    void set_error(const std::string &text);
    // Counts and (per the divisor) stores the sample just read into the write slot.
    void take(const ln_sample_info &info);

    const std::string label_;
    const uint64_t layout_hash_; // the thread's copies of what never changes
    const uint64_t message_size_;
    LoggerConfig config_; // the poll loop's

    mutable std::mutex mutex_; // guards everything below
    SampleBuffer buffer_;
    LoggerCounters counters_; // `stored` is buffer_.size()
    uint32_t divisor_;
    int64_t span_ns_;
    std::string ring_;    // where the thread (re)opens its tap
    std::string segment_; // the segment the tap is on now, "" without a tap
    std::string last_error_;
    uint64_t last_seq_ = 0; // the newest seq the tap delivered; 0: none since enabled
    // The ring's newest seq when this capture began reading it (enable, or the ring's
    // appearance): the samples after it are logged or counted as missed.
    uint64_t start_seq_ = 0;

    std::unique_ptr<Run> run_; // the poll loop's: set while enabled
};

} // namespace lnd
