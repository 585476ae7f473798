// The sending end of a TCP stream: a reader thread takes every sample from the ring's tap
// into a bounded queue (when it is full the oldest queued sample is dropped), a writer
// thread keeps a connection to the receiving daemon and sends the queue in order,
// reconnecting with back-off.  The publisher is never held up: the tap holds no reader slot
// and the reader never waits for the writer.
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

namespace lnd::fwd {

class TcpSender final : public SendStream {
public:
    // Opens the ring; "" and `out` set, or the reason (also when not even one sample fits
    // the queue bounds).
    static std::string create(const SendSpec &spec, const Options &options,
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
    };

    void read_loop();
    void write_loop();
    // Connects (and reconnects) until it succeeds or the stream stops (false).
    bool connect_with_backoff();
    std::string try_connect(); // "" with sock_ set, or what went wrong
    void lost(const std::string &why);
    Buffer take_buffer();      // a free buffer, or a new one within the bound
    void give_buffer(Buffer b); // under mutex_

    Tap tap_;
    const size_t capacity_; // samples queued plus the one being sent, at most
    const int socket_buffer_;
    const int64_t spin_ns_;          // poll the tap / the queue this long before sleeping
    std::atomic<size_t> queued_{0}; // queue_.size(), readable without the mutex

    std::mutex mutex_;
    std::condition_variable ready_;
    std::deque<Sample> queue_;
    bool in_flight_ = false;     // the writer holds a sample taken from the queue
    std::vector<Buffer> free_;   // buffers to reuse
    size_t allocated_ = 0;       // buffers in existence: at most capacity_ + 1

    UniqueFd sock_; // writer thread only
    StopSignal stop_;
    std::thread reader_, writer_;
};

} // namespace lnd::fwd
