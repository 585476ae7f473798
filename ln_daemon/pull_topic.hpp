// PullTopic: one topic served over NDN (docs/daemon.md, "Pull topics").  A thread of its own
// reads the topic's ring through an LN_TAP_EVERY tap (no reader slot: the publisher never
// waits for it) into a history of the last `history` samples, allocated and touched when the
// topic is configured.  The port's receive thread asks it to answer Interests (answer());
// Interests for a seq not published yet are parked in a fixed table and answered by the
// ring thread the moment that seq is published.  History, parked table, recent nonces and
// counters sit behind one mutex that either thread holds only briefly (no encoding, signing
// or sending under it); nothing is allocated per sample or per packet.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <ln/ndn.h>

#include "forward_net.hpp"
#include "forward_tap.hpp"
#include "outcome.hpp"
#include "pull_messages.hpp"
#include "pull_reply.hpp"

namespace lnd {

constexpr size_t kPullParked = 64; // parked Interests per topic
constexpr size_t kPullNonces = 64; // recent (name, nonce) pairs per topic
constexpr uint32_t kMaxPullHistory = 65536;
constexpr uint32_t kMaxPullParkMs = 60000; // a parked Interest waits at most this long
constexpr int64_t kPullRetryUs = 500000;   // reopening a ring that is not there (yet)
constexpr double kPullReadTimeout = 0.1;   // s: how soon the ring thread notices a stop

// What a pull topic is configured with (PULL_TOPIC, checked).
struct PullConfig {
    std::string ring;
    std::string md_name;
    uint64_t layout_hash = 0;
    uint64_t message_size = 0;
    std::string uri;           // the name as configured
    std::vector<uint8_t> name; // its name value (the components)
    uint32_t history = 1;
    uint32_t freshness_ms = 0;
    uint8_t signature = LN_NDN_SIG_DIGEST_SHA256;
    std::string key;
};

// One Interest for the topic, as the port decoded it.
struct PullInterest {
    ln_ndn_bytes name; // the Interest's whole name value
    bool sync = false; // /<name>/sync...; else a seq Interest
    uint64_t seq = 0;
    bool has_nonce = false;
    uint32_t nonce = 0;
    uint64_t name_hash = 0;
    uint32_t lifetime_ms = LN_NDN_DEFAULT_LIFETIME_MS;
    PullPeer peer;
};

class PullTopic {
public:
    using Nanos = int64_t; // steady clock

    // Allocates (and touches) the history; throws std::bad_alloc.  `label` names the topic
    // in the log ("instance I pull topic T").
    PullTopic(const PullConfig &config, std::string label);
    ~PullTopic(); // stops and joins the thread
    PullTopic(const PullTopic &) = delete;
    PullTopic &operator=(const PullTopic &) = delete;

    const PullConfig &config() const noexcept { return config_; }
    // Bytes of the history (what the daemon's pull memory limit counts).
    static uint64_t bytes_for(uint32_t history, uint64_t message_size) noexcept;
    uint64_t memory() const noexcept { return bytes_for(config_.history, config_.message_size); }
    // Same history shape and layout: reconfigure() can keep the samples.
    bool same_geometry(const PullConfig &c) const noexcept;
    // Takes a config of the same geometry; only while stopped and detached from its port
    // (nothing else reads the config then).
    void reconfigure(const PullConfig &c);

    // Starts reading the ring (a fresh tap: samples published from now on), sending the
    // answers to parked Interests from `fd`.  Throws std::system_error if no thread can be
    // made.  A ring that cannot be opened goes to last_error; the thread retries every
    // kPullRetryUs.
    void start(int fd);
    void request_stop() noexcept;
    void join() noexcept;
    bool running() const noexcept { return run_ != nullptr; }

    // The port thread: answers one Interest (now, or by parking it) through `sender`;
    // false if a send failed (the sender's errno in `error`, with the peer's address).
    bool answer(const PullInterest &in, Nanos now, PullSender &sender, ErrorText &error);
    // The port thread: drops (and counts) parked Interests that expired by `now`; returns
    // when the next one expires (INT64_MAX if none is parked).
    Nanos expire(Nanos now);

    PullTopicStatus status() const; // topic, address and port left empty

    static Nanos now() noexcept;
    static uint64_t hash_name(ln_ndn_bytes name) noexcept;

private:
    struct Run {
        fwd::StopSignal stop;
        std::thread thread;
    };
    struct Slot { // one history entry; seq 0: empty
        uint64_t seq = 0;
        uint64_t publish_us = 0;
    };
    struct Parked {
        bool used = false;
        uint64_t seq = 0;
        Nanos expiry = 0;
        uint32_t nonce = 0;
        PullPeer peer;
    };
    struct Seen {
        uint64_t hash = 0;
        uint32_t nonce = 0;
        bool used = false;
    };
    // What answer() decided under the lock.
    enum class Verdict { parked, data, nack };

    void loop(Run &run, fwd::Tap tap);
    // A tap that delivers the ring's newest sample, then every later one: a topic that
    // published before it was served, or publishes rarely, answers at once.  "" or why
    // the ring cannot be opened.
    Outcome open_tap(fwd::Tap &tap) const;
    void set_error(const char *text);
    // Stores the sample just read into the sender's payload buffer and answers the
    // Interests parked for it (and NACKs those it passed over).
    void publish(const ln_sample_info &info);
    // Under the lock: whether (hash, nonce) was seen recently; remembers it.
    bool seen_before(uint64_t hash, uint32_t nonce) noexcept;
    // Under the lock: the history slot holding `seq`, or nullptr.
    const Slot *stored(uint64_t seq) const noexcept;
    ln_ndn_signer signer() const noexcept;
    // Encodes a NACK (the topic's newest seq `latest`) for `name`; LN_NDN_OK or an error.
    int encode_nack(PullSender &sender, ln_ndn_bytes name, uint64_t latest) const noexcept;
    // Takes back the count of a Data (or NACK) reply that could not be sent.
    void uncount(bool data) noexcept;

    const std::string label_;
    PullConfig config_;
    PullSender sender_; // the ring thread's: answers to parked Interests

    mutable std::mutex mutex_;   // guards everything below
    std::vector<Slot> slots_;    // slot seq % history
    std::vector<uint8_t> bytes_; // history × message_size
    uint64_t latest_ = 0;        // newest seq stored, 0: none yet
    int64_t last_stamp_ns_ = 0;  // of the newest sample
    double period_us_ = 0;       // EWMA of the publish period
    std::array<Parked, kPullParked> parked_{};
    std::array<Seen, kPullNonces> seen_{};
    size_t seen_next_ = 0;
    PullTopicCounters counters_;
    ErrorText error_; // the current problem ("" if none)

    std::unique_ptr<Run> run_; // the poll loop's: set while started
};

} // namespace lnd
