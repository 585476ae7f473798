// The ring thread and the reply rules of one pull topic (pull_topic.hpp).  Both threads
// decide under the topic's mutex and copy what a reply needs (the sample's bytes, the
// consumer's address) into their own sender's buffers; they encode, sign and send after
// letting go of it.  A reply is counted before it goes (so whoever received it finds it
// counted) and taken back if it could not be sent.
#include "pull_topic.hpp"

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <climits>
#include <cstring>
#include <sys/prctl.h>

#include "log.hpp"

namespace lnd {

namespace {

bool same_peer(const PullPeer &a, const PullPeer &b) noexcept
{
    return a.addr_len == b.addr_len && std::memcmp(&a.addr, &b.addr, a.addr_len) == 0;
}

// The largest name value a configured URI gives: the URI's bytes plus a TLV header per
// component, generously.
size_t name_room(const PullConfig &c) noexcept { return c.name.size() + 64; }

} // namespace

PullTopic::PullTopic(const PullConfig &config, std::string label)
    : label_(std::move(label)), config_(config), sender_(config.message_size, name_room(config)),
      slots_(config.history),
      bytes_(config.history * config.message_size) // zeroed: every page touched now
{}

PullTopic::~PullTopic()
{
    request_stop();
    join();
}

uint64_t PullTopic::bytes_for(uint32_t history, uint64_t message_size) noexcept
{
    return uint64_t{history} * (message_size + sizeof(Slot));
}

bool PullTopic::same_geometry(const PullConfig &c) const noexcept
{
    return c.message_size == config_.message_size && c.history == config_.history &&
           c.layout_hash == config_.layout_hash;
}

void PullTopic::reconfigure(const PullConfig &c)
{
    if (c.name.size() > config_.name.size())
        sender_ = PullSender(c.message_size, name_room(c));
    config_ = c;
}

PullTopic::Nanos PullTopic::now() noexcept
{
    return std::chrono::duration_cast<std::chrono::nanoseconds>(
               std::chrono::steady_clock::now().time_since_epoch())
        .count();
}

uint64_t PullTopic::hash_name(ln_ndn_bytes name) noexcept
{
    uint64_t h = 0xcbf29ce484222325ull; // FNV-1a
    for (size_t i = 0; i < name.size; ++i) {
        h ^= name.data[i];
        h *= 0x100000001b3ull;
    }
    return h;
}

// ---- the poll loop's side ------------------------------------------------------------------

void PullTopic::start(int fd)
{
    if (run_)
        return;
    sender_.set_fd(fd);
    fwd::Tap tap;
    set_error(open_tap(tap).text.c_str());
    auto run = std::make_unique<Run>();
    Run &r = *run;
    r.thread = std::thread([this, &r, t = std::move(tap)]() mutable { loop(r, std::move(t)); });
    run_ = std::move(run);
}

void PullTopic::request_stop() noexcept
{
    if (run_)
        run_->stop.raise();
}

void PullTopic::join() noexcept
{
    if (!run_)
        return;
    if (run_->thread.joinable())
        run_->thread.join();
    run_.reset();
}

PullTopicStatus PullTopic::status() const
{
    PullTopicStatus s;
    s.name = config_.uri;
    s.ring = config_.ring;
    s.history = config_.history;
    std::lock_guard<std::mutex> lock(mutex_);
    s.latest_seq = latest_;
    s.counters = counters_;
    s.last_error = error_.text;
    return s;
}

// ---- the ring thread -----------------------------------------------------------------------

Outcome PullTopic::open_tap(fwd::Tap &tap) const
{
    ln_ring_tap *t = nullptr;
    int rc = ln_ring_tap_open(&t, config_.ring.c_str(), config_.layout_hash, config_.message_size,
                              LN_TAP_EVERY | LN_TAP_INCLUDE_NEWEST);
    if (rc != LN_OK)
        return outcome::error(proto::Err::pull_failed, "cannot open ring '" + config_.ring +
                                                           "': " + ln_error_name(rc) + ": " +
                                                           ln_last_error());
    tap.reset(t);
    return outcome::ok();
}

void PullTopic::set_error(const char *text)
{
    bool changed;
    {
        std::lock_guard<std::mutex> lock(mutex_);
        changed = error_.set("%s", text);
    }
    if (changed && *text) // once per change, not once per retry
        logf("%s: %s", label_.c_str(), text);
}

void PullTopic::loop(Run &run, fwd::Tap tap)
{
    ::prctl(PR_SET_TIMERSLACK, 1000UL); // 1 µs: a parked Interest is answered at once
    while (!run.stop.raised()) {
        if (!tap) {
            set_error(open_tap(tap).text.c_str());
            if (!tap) {
                run.stop.sleep_us(kPullRetryUs);
                continue;
            }
        }
        ln_sample_info info;
        int rc = ln_ring_tap_read(tap.get(), sender_.payload(), &info, kPullReadTimeout);
        if (rc == LN_OK) {
            publish(info);
        } else if (rc != LN_ETIMEOUT) {
            set_error((std::string("cannot read ring '") + ln_ring_tap_segment(tap.get()) +
                       "': " + ln_error_name(rc) + ": " + ln_last_error())
                          .c_str());
            tap.reset();
            run.stop.sleep_us(kPullRetryUs);
        }
    }
}

void PullTopic::publish(const ln_sample_info &info)
{
    const uint64_t seq = info.seq;
    const uint64_t publish_us = info.timestamp_ns > 0 ? uint64_t(info.timestamp_ns) / 1000 : 0;
    PullPeer data_to[kPullParked], nack_to[kPullParked];
    uint64_t nack_seq[kPullParked];
    size_t n_data = 0, n_nack = 0;
    uint64_t period_us;
    {
        std::lock_guard<std::mutex> lock(mutex_);
        if (seq == latest_) // a reopened tap starts at the newest sample: stored already
            return;
        if (seq < latest_) { // the topic's numbering started afresh (a new ring)
            std::fill(slots_.begin(), slots_.end(), Slot());
            latest_ = 0;
            period_us_ = 0;
        }
        if (latest_ && info.timestamp_ns > last_stamp_ns_) {
            double per = double(info.timestamp_ns - last_stamp_ns_) / 1e3 / double(seq - latest_);
            period_us_ = period_us_ > 0 ? period_us_ + (per - period_us_) / 8 : per;
        }
        Slot &slot = slots_[seq % config_.history];
        slot.seq = seq;
        slot.publish_us = publish_us;
        std::memcpy(&bytes_[(seq % config_.history) * config_.message_size], sender_.payload(),
                    config_.message_size);
        latest_ = seq;
        last_stamp_ns_ = info.timestamp_ns;
        period_us = static_cast<uint64_t>(period_us_ + 0.5);
        for (Parked &p : parked_) {
            if (!p.used || p.seq > seq)
                continue;
            if (p.seq == seq)
                data_to[n_data++] = p.peer;
            else { // passed over (the tap missed it): it will never come
                nack_to[n_nack] = p.peer;
                nack_seq[n_nack++] = p.seq;
            }
            p.used = false;
        }
        counters_.data += n_data;  // counted before they go, so a consumer never sees a
        counters_.nacks += n_nack; // reply its counter lacks; failures are taken back
    }
    if (n_data == 0 && n_nack == 0)
        return;
    const ln_ndn_signer sig = signer();
    const ln_ndn_bytes base{config_.name.data(), config_.name.size()};
    uint64_t failed_data = 0, failed_nacks = 0;
    int send_err = 0, encode_err = LN_NDN_OK;
    char where[64] = "";
    auto send = [&](const PullPeer &peer, uint64_t &failed) {
        int e = sender_.send(peer);
        if (e == 0)
            return;
        ++failed;
        if (!send_err) {
            send_err = e;
            peer_text(peer.addr, where, sizeof where);
        }
    };
    if (n_data) {
        ln_ndn_pull_content c{};
        c.latest_seq = seq;
        c.publish_us = publish_us;
        c.period_us = period_us;
        c.payload = {sender_.payload(), config_.message_size};
        int rc = sender_.encode(sender_.name_with_seq(base, seq), LN_NDN_CONTENT_BLOB,
                                config_.freshness_ms, c, sig);
        if (rc == LN_NDN_OK) {
            for (size_t i = 0; i < n_data; ++i)
                send(data_to[i], failed_data);
        } else {
            encode_err = rc;
            failed_data = n_data;
        }
    }
    for (size_t i = 0; i < n_nack; ++i) {
        int rc = encode_nack(sender_, sender_.name_with_seq(base, nack_seq[i]), seq);
        if (rc == LN_NDN_OK) {
            send(nack_to[i], failed_nacks);
        } else {
            encode_err = rc;
            ++failed_nacks;
        }
    }
    if (!failed_data && !failed_nacks)
        return;
    std::lock_guard<std::mutex> lock(mutex_);
    counters_.data -= failed_data;
    counters_.nacks -= failed_nacks;
    if (send_err)
        error_.set("cannot send to %s: %s", where, std::strerror(send_err));
    else if (encode_err != LN_NDN_OK)
        error_.set("cannot encode a reply: %s", ln_ndn_strerror(encode_err));
}

// ---- the port thread -----------------------------------------------------------------------

ln_ndn_signer PullTopic::signer() const noexcept
{
    ln_ndn_signer s{};
    s.type = config_.signature;
    s.key = reinterpret_cast<const uint8_t *>(config_.key.data());
    s.key_size = config_.key.size();
    return s;
}

int PullTopic::encode_nack(PullSender &sender, ln_ndn_bytes name, uint64_t latest) const noexcept
{
    ln_ndn_pull_content c{};
    c.latest_seq = latest;
    return sender.encode(name, LN_NDN_CONTENT_NACK, 0, c, signer());
}

bool PullTopic::seen_before(uint64_t hash, uint32_t nonce) noexcept
{
    for (const Seen &s : seen_)
        if (s.used && s.hash == hash && s.nonce == nonce)
            return true;
    seen_[seen_next_] = {hash, nonce, true};
    seen_next_ = (seen_next_ + 1) % seen_.size();
    return false;
}

const PullTopic::Slot *PullTopic::stored(uint64_t seq) const noexcept
{
    const Slot &s = slots_[seq % config_.history];
    return s.seq == seq && seq != 0 ? &s : nullptr;
}

void PullTopic::uncount(bool data) noexcept
{
    std::lock_guard<std::mutex> lock(mutex_);
    --(data ? counters_.data : counters_.nacks);
}

bool PullTopic::answer(const PullInterest &in, Nanos now, PullSender &sender, ErrorText &error)
{
    Verdict verdict = Verdict::nack;
    uint64_t latest, seq = 0, publish_us = 0, period_us = 0;
    {
        std::lock_guard<std::mutex> lock(mutex_);
        ++counters_.interests;
        counters_.syncs += in.sync;
        if (in.has_nonce && seen_before(in.name_hash, in.nonce)) {
            ++counters_.duplicates;
            return true;
        }
        latest = latest_;
        period_us = static_cast<uint64_t>(period_us_ + 0.5);
        const Slot *slot = nullptr;
        if (latest == 0) {
            verdict = Verdict::nack; // no sample yet: latest 0
        } else if (in.sync || in.seq <= latest) {
            seq = in.sync ? latest : in.seq;
            slot = stored(seq); // the newest is always stored; an older one maybe not
            verdict = slot ? Verdict::data : Verdict::nack;
        } else if (in.seq - latest <= config_.history) {
            Parked *free = nullptr, *same = nullptr;
            for (Parked &p : parked_) {
                if (p.used && p.seq == in.seq && same_peer(p.peer, in.peer))
                    same = &p; // a retransmission from the same consumer takes its place
                else if (!p.used && !free)
                    free = &p;
            }
            Parked *entry = same ? same : free;
            if (entry) {
                uint32_t ms = std::min(in.lifetime_ms, kMaxPullParkMs);
                *entry = {true, in.seq, now + Nanos(ms) * 1000000, in.nonce, in.peer};
                ++counters_.parked;
                verdict = Verdict::parked;
            } else {
                ++counters_.overflow;
                verdict = Verdict::nack;
            }
        } else {
            verdict = Verdict::nack; // too far ahead
        }
        counters_.data += verdict == Verdict::data;
        counters_.nacks += verdict == Verdict::nack;
        if (slot) {
            publish_us = slot->publish_us;
            std::memcpy(sender.payload(), &bytes_[(seq % config_.history) * config_.message_size],
                        config_.message_size);
        }
    }
    if (verdict == Verdict::parked)
        return true;
    int rc;
    if (verdict == Verdict::data) {
        ln_ndn_pull_content c{};
        c.latest_seq = latest;
        c.publish_us = publish_us;
        c.period_us = period_us;
        c.payload = {sender.payload(), config_.message_size};
        ln_ndn_bytes name = in.sync ? sender.name_with_seq(in.name, seq) : in.name;
        rc = sender.encode(name, LN_NDN_CONTENT_BLOB, in.sync ? 0 : config_.freshness_ms, c,
                           signer());
    } else {
        rc = encode_nack(sender, in.name, latest);
    }
    if (rc != LN_NDN_OK) {
        uncount(verdict == Verdict::data);
        error.set("cannot encode a reply for %s: %s", label_.c_str(), ln_ndn_strerror(rc));
        return false;
    }
    int e = sender.send(in.peer);
    if (e != 0) {
        uncount(verdict == Verdict::data);
        char where[64];
        peer_text(in.peer.addr, where, sizeof where);
        error.set("cannot send to %s: %s", where, std::strerror(e));
        return false;
    }
    return true;
}

PullTopic::Nanos PullTopic::expire(Nanos now)
{
    Nanos next = INT64_MAX;
    std::lock_guard<std::mutex> lock(mutex_);
    for (Parked &p : parked_) {
        if (!p.used)
            continue;
        if (p.expiry <= now) {
            p.used = false;
            ++counters_.expired;
        } else {
            next = std::min(next, p.expiry);
        }
    }
    return next;
}

} // namespace lnd
