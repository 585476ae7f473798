// The reading thread and the poll loop's side of one logger topic (logger_topic.hpp).  The
// thread reads each sample straight into the buffer's write slot, outside the mutex, and
// takes the mutex only to count it and commit it; a fetch copies under the same mutex, so
// it sees every sample whole and the counters as of the same moment.
#include "logger_topic.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sys/prctl.h>

#include "log.hpp"

namespace lnd {

namespace {

using Clock = std::chrono::steady_clock;

int64_t us_between(Clock::time_point a, Clock::time_point b) noexcept
{
    return std::chrono::duration_cast<std::chrono::microseconds>(b - a).count();
}

int64_t span_ns(double span_s) noexcept
{
    return span_s > 0 ? static_cast<int64_t>(std::llround(span_s * 1e9)) : 0;
}

// Slots of the ring `segment` (0 if its header cannot be read).
uint32_t ring_slots(const char *segment) noexcept
{
    ln_ring_admin *admin = nullptr;
    if (ln_ring_admin_open(&admin, segment) != LN_OK)
        return 0;
    ln_ring_info info;
    uint32_t slots = ln_ring_admin_info(admin, &info) == LN_OK ? info.slot_count : 0;
    ln_ring_admin_close(admin);
    return slots;
}

// How the reading thread waits for samples (logger_topic.hpp).  The topic's rate is a
// decaying average over the recent looks at the ring (a single look's count depends on where
// the samples fell between looks).  The thread sleeps on the ring's futex until the rate
// exceeds kLoggerPollAbove and polls until it falls below kLoggerWaitBelow (so a topic near
// one rate does not switch back and forth).  Polling, it sleeps for the time in which a
// quarter of the ring's slots fill at that rate (or at the rate of the last look, if
// higher), growing the interval at most twofold per look; at a rate that fills the ring
// four times over in the shortest interval, every kLoggerSaturatedPollUs.
class Pacer {
public:
    explicit Pacer(Clock::time_point now) : last_look_(now) {}

    bool futex() const noexcept { return futex_; }

    // After a look that found `advance` sequence numbers (samples and the gaps before them)
    // in a ring of `slots` slots (0: unknown): how long to sleep before the next look.
    int64_t next(Clock::time_point now, uint64_t advance, uint32_t slots) noexcept
    {
        double dt = static_cast<double>(std::max<int64_t>(us_between(last_look_, now), 1));
        last_look_ = now;
        seqs_ = seqs_ * kDecay + static_cast<double>(advance);
        time_ = time_ * kDecay + dt;
        double quarter = std::max<uint32_t>(slots, 2) / 4.0;
        double target = seqs_ > 0 ? time_ * quarter / seqs_ : double(kLoggerMaxPollUs);
        if (advance)
            target = std::min(target, dt * quarter / static_cast<double>(advance));
        target = std::min(target, 2.0 * static_cast<double>(interval_));
        interval_ = std::clamp(static_cast<int64_t>(target), kLoggerMinPollUs, kLoggerMaxPollUs);
        double r = rate();
        futex_ = futex_ ? r <= kLoggerPollAbove : r < kLoggerWaitBelow;
        if (r * kLoggerMinPollUs / 1e6 > 4.0 * std::max<uint32_t>(slots, 2))
            interval_ = kLoggerSaturatedPollUs; // hopeless: see kLoggerSaturatedPollUs
        return interval_;
    }

private:
    static constexpr double kDecay = 0.8; // weight of the looks before, per look

    double rate() const noexcept { return time_ > 0 ? seqs_ * 1e6 / time_ : 0; }

    Clock::time_point last_look_;
    double seqs_ = 0, time_ = 0; // decaying sums of sequence numbers and of µs
    int64_t interval_ = kLoggerMinPollUs;
    bool futex_ = true;
};

} // namespace

LoggerTopic::LoggerTopic(const LoggerConfig &config, std::string label)
    : label_(std::move(label)), layout_hash_(config.layout_hash),
      message_size_(config.message_size), config_(config),
      buffer_(config.depth, config.message_size), divisor_(config.divisor),
      span_ns_(span_ns(config.span_s)), ring_(config.ring)
{}

LoggerTopic::~LoggerTopic()
{
    request_stop();
    join();
}

bool LoggerTopic::same_geometry(const LoggerConfig &c) const noexcept
{
    return c.message_size == config_.message_size && c.depth == config_.depth &&
           c.layout_hash == config_.layout_hash;
}

void LoggerTopic::update(const LoggerConfig &c)
{
    bool moved = c.ring != config_.ring;
    config_ = c;
    std::string segment;
    {
        std::lock_guard<std::mutex> lock(mutex_);
        divisor_ = c.divisor;
        span_ns_ = span_ns(c.span_s);
        ring_ = c.ring;
        segment = segment_;
    }
    if (moved && run_ && segment != c.ring) {
        request_stop();
        join();
        start_run(true);
    }
}

void LoggerTopic::start()
{
    if (!run_)
        start_run(false);
}

void LoggerTopic::start_run(bool keep_baseline)
{
    std::string ring;
    {
        std::lock_guard<std::mutex> lock(mutex_);
        if (!keep_baseline)
            last_seq_ = start_seq_ = 0; // what was published while disabled is not missed
        ring = ring_;
    }
    fwd::Tap tap;
    set_error(open_tap(tap, ring).text);
    if (tap) {
        began(tap.get());
        std::lock_guard<std::mutex> lock(mutex_);
        segment_ = ln_ring_tap_segment(tap.get());
    }
    auto run = std::make_unique<Run>();
    Run &r = *run;
    r.thread = std::thread([this, &r, t = std::move(tap)]() mutable { loop(r, std::move(t)); });
    run_ = std::move(run);
}

void LoggerTopic::began(ln_ring_tap *tap)
{
    uint64_t newest = ln_ring_tap_write_seq(tap);
    std::lock_guard<std::mutex> lock(mutex_);
    if (last_seq_ == 0)
        last_seq_ = start_seq_ = newest;
}

void LoggerTopic::request_stop() noexcept
{
    if (run_)
        run_->stop.raise();
}

void LoggerTopic::join() noexcept
{
    if (!run_)
        return;
    if (run_->thread.joinable())
        run_->thread.join();
    run_.reset();
    std::lock_guard<std::mutex> lock(mutex_);
    segment_.clear();
}

void LoggerTopic::clear()
{
    std::lock_guard<std::mutex> lock(mutex_);
    buffer_.clear();
    counters_ = LoggerCounters();
}

LoggerTopicStatus LoggerTopic::status() const
{
    LoggerTopicStatus s;
    s.ring = config_.ring;
    s.md_name = config_.md_name;
    s.enabled = running();
    s.depth = config_.depth;
    s.divisor = config_.divisor;
    s.span_s = config_.span_s;
    s.message_size = config_.message_size;
    std::lock_guard<std::mutex> lock(mutex_);
    s.counters = counters_;
    s.counters.stored = buffer_.size();
    s.last_error = last_error_;
    return s;
}

void LoggerTopic::fetch(proto::Writer &w, uint64_t after_seq, uint32_t max_bytes) const
{
    const uint64_t per = logger_sample_wire_bytes(config_.message_size);
    const uint64_t room = (kMaxReplyPayload - kLoggerDataHeadBytes) / per; // >= 1: checked
    uint64_t n = std::clamp<uint64_t>(max_bytes / per, 1, room);           // when configured
    n = std::min<uint64_t>(n, config_.depth);
    w.buffer().reserve(kLoggerDataHeadBytes + n * per); // no allocation under the mutex
    LoggerDataHead head;
    head.message_size = config_.message_size;
    head.layout_hash = config_.layout_hash;
    head.md_name = config_.md_name;
    head.enabled = running();
    std::lock_guard<std::mutex> lock(mutex_);
    head.counters = counters_;
    head.counters.stored = buffer_.size();
    head.first_seq = buffer_.first_seq();
    head.last_seq = buffer_.last_seq();
    head.start_seq = start_seq_;
    encode_logger_data_head(w, head);
    buffer_.encode_after(w, after_seq, static_cast<uint32_t>(n));
}

Outcome LoggerTopic::open_tap(fwd::Tap &tap, const std::string &ring) const
{
    ln_ring_tap *t = nullptr;
    int rc = ln_ring_tap_open(&t, ring.c_str(), layout_hash_, message_size_, LN_TAP_EVERY);
    if (rc != LN_OK)
        return outcome::error(proto::Err::logger_failed, "cannot open ring '" + ring +
                                                             "': " + ln_error_name(rc) + ": " +
                                                             ln_last_error());
    tap.reset(t);
    return outcome::ok();
}

uint32_t LoggerTopic::note_segment(ln_ring_tap *tap, std::string &seen)
{
    const char *now = ln_ring_tap_segment(tap);
    if (!now || seen == now)
        return 0;
    seen = now;
    {
        std::lock_guard<std::mutex> lock(mutex_);
        segment_ = seen;
    }
    return ring_slots(now);
}

void LoggerTopic::set_error(const std::string &text)
{
    {
        std::lock_guard<std::mutex> lock(mutex_);
        if (last_error_ == text)
            return;
        last_error_ = text;
    }
    if (!text.empty()) // once per change, not once per retry
        logf("%s: %s", label_.c_str(), text.c_str());
}

void LoggerTopic::take(const ln_sample_info &info)
{
    std::lock_guard<std::mutex> lock(mutex_);
    ++counters_.received;
    // Within one tap the gap is its overruns; across a reopen of the tap (a new ring, a
    // read error) it is the distance to the last sample seen.
    counters_.missed +=
        last_seq_ && info.seq > last_seq_ ? info.seq - last_seq_ - 1 : info.overruns;
    last_seq_ = info.seq;
    if (info.seq % divisor_ != 0) {
        ++counters_.skipped;
        return;
    }
    counters_.dropped += buffer_.commit(info.seq, info.timestamp_ns, span_ns_);
}

void LoggerTopic::loop(Run &run, fwd::Tap tap)
{
    ::prctl(PR_SET_TIMERSLACK, 1000UL); // 1 µs: short poll intervals stay short
    std::string seen;                   // the tap's segment as last noted
    uint32_t slots = 0;
    if (tap)
        slots = note_segment(tap.get(), seen);
    Pacer pacer(Clock::now());
    while (!run.stop.raised()) {
        if (!tap) {
            std::string ring;
            {
                std::lock_guard<std::mutex> lock(mutex_);
                ring = ring_;
            }
            set_error(open_tap(tap, ring).text);
            if (!tap) {
                run.stop.sleep_us(kLoggerRetryUs);
                continue;
            }
            began(tap.get());
            seen.clear();
            pacer = Pacer(Clock::now());
        }
        // Slowly: wait on the futex for the first sample (up to 0.1 s, to notice a stop).
        // Fast: take what came since the last look without waiting.
        bool futex = pacer.futex();
        // At most a ring's worth per look: a publisher that fills the ring faster than the
        // logger reads it is not chased (that would only contend for its cache lines).
        const uint64_t most = std::max<uint32_t>(slots, 2);
        ln_sample_info info;
        int rc;
        uint64_t n = 0, advance = 0; // samples, and sequence numbers with the gaps
        while ((rc = ln_ring_tap_read(tap.get(), buffer_.write_slot(), &info,
                                      n == 0 && futex ? 0.1 : 0)) == LN_OK) {
            take(info);
            advance += 1 + info.overruns;
            if (++n >= most)
                break;
        }
        if (rc != LN_OK && rc != LN_ETIMEOUT) {
            set_error(std::string("cannot read ring '") + ln_ring_tap_segment(tap.get()) +
                      "': " + ln_error_name(rc) + ": " + ln_last_error());
            tap.reset();
            {
                std::lock_guard<std::mutex> lock(mutex_);
                segment_.clear();
            }
            run.stop.sleep_us(kLoggerRetryUs);
            continue;
        }
        if (uint32_t s = note_segment(tap.get(), seen))
            slots = s;
        int64_t interval = pacer.next(Clock::now(), advance, slots);
        if (!pacer.futex())
            run.stop.sleep_us(interval);
    }
}

} // namespace lnd
