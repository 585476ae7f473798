// The sending end of a UDP stream: one thread reads the newest sample from the ring's tap
// and sends it at once, cut into fragments, with sendmmsg in batches (paced when the stream
// has a rate limit), runs of fragments handed to the kernel as one message that it cuts
// into datagrams (UDP_SEGMENT, where the kernel offers it).  Each datagram carries the
// stream's salt and its own counter and ends in a tag (forward_crypto.hpp); with `encrypt`
// the payload is the cipher text of a per-sample buffer.  Nothing is queued: a sample published while the previous one is still
// being sent is skipped if a newer one follows before the send ends (counted in drops).
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <sys/socket.h>
#include <thread>
#include <vector>

#include "fd.hpp"
#include "forward_net.hpp"
#include "forward_send_stream.hpp"
#include "forward_tap.hpp"

namespace lnd::fwd {

class UdpSender final : public SendStream {
public:
    // Opens the ring into `out`, or refuses (error stream_failed).
    static Outcome create(const SendSpec &spec, const Options &options,
                          std::unique_ptr<SendStream> &out);
    UdpSender(const SendSpec &spec, const Options &options, Tap tap);
    // A salt greater than any this host chose before for any stream: the wall clock in
    // microseconds, then 12 random bits (a receiver takes only a newer salt, see
    // forward_udp_recv.cpp).
    static uint64_t fresh_salt() noexcept;
    ~UdpSender() override;

    void start() override;
    void stop() noexcept override;
    void join() noexcept override;

private:
    enum class Sent { ok, failed, stopped };

    void run();
    Sent send_sample(uint64_t seq, int64_t timestamp_ns);
    // (Re)resolves the destination and makes a connected socket for it; a failure keeps the
    // previous socket, if any.  Resolving happens at most once per kResolveInterval.
    void open_socket();
    // With a rate limit: waits until `bytes` more may go; false if stopped meanwhile.
    bool pace(size_t bytes);
    void new_salt(); // a fresh salt and its key; the counter starts again at 1

    Tap tap_;
    const uint16_t chunk_;
    const int socket_buffer_;
    const int64_t spin_ns_;   // poll the tap this long before sleeping
    const double rate_;       // bytes per second, 0: no limit
    const unsigned batch_;    // datagrams per sendmmsg
    const unsigned segments_; // datagrams per message with segmentation offload
    const sec::Suite suite_;
    const size_t tag_size_; // bytes after each payload
    Key stream_key_;
    std::unique_ptr<sec::Box> box_; // the key of salt_
    uint64_t salt_ = 0;
    uint64_t counter_ = 0;              // of the last datagram sent under salt_
    std::unique_ptr<uint8_t[]> cipher_; // encrypt: the sample's cipher text
    std::vector<uint8_t> tags_;         // per datagram of a batch
    bool gso_ = true;                   // UDP_SEGMENT works here (cleared at its first refusal)
    double credit_ = 0;                 // bytes that may go now (token bucket)
    std::chrono::steady_clock::time_point last_pace_{};
    std::unique_ptr<uint8_t[]> sample_;
    UniqueFd sock_;
    bool reopen_ = true; // the next sample first resolves and opens again
    std::chrono::steady_clock::time_point next_open_{};
    std::vector<uint8_t> headers_;
    std::vector<mmsghdr> msgs_;
    std::vector<iovec> iov_;
    std::vector<std::array<char, CMSG_SPACE(sizeof(uint16_t))>> control_; // per message
    StopSignal stop_;
    std::thread thread_;
};

} // namespace lnd::fwd
