// The sending end of a TCP stream: a reader thread takes every sample from the ring's tap
// into a bounded queue (when it is full the oldest queued sample is dropped), a writer
// thread keeps a connection to the receiving daemon and sends the queue in order,
// reconnecting with back-off.  When the writer is idle on a healthy connection and nothing
// is queued, the reader sends the sample itself (no thread wake-up): a small one copied out
// and without blocking, queueing what the socket did not take at once; a large one straight
// from the ring slot (no copy; encrypt: enciphered from it), waiting up to 200 ms for room
// in the socket (the ring is the queue, so a publisher faster than the link costs no copies
// that are dropped later, only samples the stream overruns, counted; a receiver that stopped
// reading costs the queue's bound).  The frame's trailer says whether
// the slot stayed intact while it was sent (the publisher overwrites it only when the
// stream falls a whole ring behind); a torn frame is dropped by the receiver and counted as
// a drop here.  With a security level other than none every frame ends in a tag under a
// key of the connection (forward_tcp_frame.hpp), taken while the slot is borrowed.  The
// publisher is never held up: the tap holds no reader slot and the reader never waits for
// the writer or the network.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "fd.hpp"
#include "forward_net.hpp"
#include "forward_send_stream.hpp"
#include "forward_tap.hpp"
#include "outcome.hpp"

namespace lnd::fwd {

class TcpSender final : public SendStream {
public:
    // Opens the ring into `out`, or refuses (error stream_failed) (also when not even one sample fits
    // the queue bounds).
    static Outcome create(const SendSpec &spec, const Options &options,
                          std::unique_ptr<SendStream> &out);
    TcpSender(const SendSpec &spec, const Options &options, Tap tap, size_t capacity);
    ~TcpSender() override;

    void start() override;
    void stop() noexcept override;
    void join() noexcept override;

private:
    using Buffer = std::unique_ptr<uint8_t[]>;
    struct Sample {
        uint64_t seq = 0;
        int64_t timestamp_ns = 0;
        Buffer data;
        size_t sent = 0;    // bytes of its frame already written on the current connection
        bool intact = true; // false: the payload was overwritten while sent (trailer: torn)
        bool whole = true;  // `data` holds the sample (false: sent from the slot up to its
                            // trailer, so it cannot be sent again on a new connection)
    };

    void read_loop();
    void write_loop();
    // Reader: sends the sample at once if the writer is idle with nothing queued: `borrowed`
    // from the ring (released here), or copied into `buf` (borrowed == nullptr); true if it
    // was dealt with (sent whole, dropped as torn, or queued in `buf` with what part of it
    // went out).
    bool send_direct(const void *borrowed, Buffer &buf, const ln_sample_info &info);
    // Whether the borrowed sample `seq` is about to be overwritten (the stream is about a
    // whole ring behind) and is not the newest: then it is skipped rather than sent torn.
    bool about_to_go(uint64_t seq);
    // Counts a frame written whole: a sample, or a drop if it was torn.
    void count_sent(const Sample &s);
    // The frame of `s` (header, payload, trailer, tag) from byte s.sent on, as 1 to 4 iovecs.
    size_t frame_iov(uint8_t *header, uint8_t *trailer, const uint8_t *payload, const Sample &s,
                     iovec iov[4]) const;
    // With a key: tags (and encrypts) the frame of `s` when none of it was sent yet, else
    // keeps what was sealed for it; returns the payload to send (the cipher text or `plain`).
    const uint8_t *seal(const Sample &s, const uint8_t *header, const uint8_t *trailer,
                        const uint8_t *plain);
    size_t frame_size() const noexcept;
    // Writer: writes `s` from s.sent on; Io::ok once all of it went out.
    Io write_sample(Sample &s, std::string &error);
    // Connects (and reconnects) until it succeeds or the stream stops (false).
    bool connect_with_backoff();
    Outcome try_connect(); // sock_ set, or refused with what went wrong
    void lost(const std::string &why);
    Buffer take_buffer();       // a free buffer, or a new one within the bound
    void give_buffer(Buffer b); // under mutex_

    Tap tap_;
    const size_t capacity_; // samples queued plus the one being sent, at most
    const int socket_buffer_;
    const int64_t spin_ns_;         // poll the tap / the queue this long before sleeping
    std::atomic<size_t> queued_{0}; // queue_.size(), readable without the mutex

    std::mutex mutex_;
    std::condition_variable ready_;
    std::deque<Sample> queue_;
    bool in_flight_ = false;      // a sample taken from the queue (or sent directly) is being sent
    bool writer_idle_ = false;    // the writer waits for the queue with sock_ connected
    bool reader_sending_ = false; // the reader writes to sock_ (the writer leaves it alone)
    std::vector<Buffer> free_;    // buffers to reuse
    size_t allocated_ = 0;        // buffers in existence: at most capacity_ + 1

    UniqueFd sock_; // the writer's; the reader uses it only while reader_sending_
    // The connection's key and what was sealed last, used like sock_.
    const sec::Suite suite_;
    Key stream_key_;
    std::unique_ptr<sec::Box> box_;
    uint64_t counter_ = 0;              // frames written whole on this connection
    std::unique_ptr<uint8_t[]> cipher_; // encrypt: the payload of the frame being sent
    uint8_t tag_[sec::kTagBytes] = {};  // of the frame being sent
    StopSignal stop_;
    std::thread reader_, writer_;
};

} // namespace lnd::fwd
