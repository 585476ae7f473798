// The UDP sending thread (forward_udp_send.hpp).  The data path is tap read -> sendmmsg on
// a connected socket, no copies besides the tap's: each datagram is two iovecs, its header
// and its slice of the sample buffer.
#include "forward_udp_send.hpp"

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <netinet/in.h>
#include <netinet/udp.h>
#include <poll.h>
#include <sodium.h>
#include <time.h>

#include "forward_wire.hpp"

namespace lnd::fwd {

namespace {

constexpr unsigned kBatch = 64; // datagrams per sendmmsg
constexpr auto kResolveInterval = std::chrono::seconds(1);
constexpr int kRefusedRetries = 3;                          // per sample, see send_sample
constexpr int64_t kMinBackoffUs = 50, kMaxBackoffUs = 5000; // after ENOBUFS
constexpr double kBurstBytes = 64 * 1024; // with a rate limit: sent at once, at most
#ifndef UDP_SEGMENT
#define UDP_SEGMENT 103
#endif

// Datagrams one send hands the kernel to cut (UDP_SEGMENT): what fits one IP datagram of
// 64 KiB; 1 (no segmentation offload) for datagrams too large to gain from it.
unsigned segments_per_send(size_t datagram)
{
    return static_cast<unsigned>(std::clamp<size_t>(wire::kMaxDatagram / datagram, 1, 64));
}

// Datagrams per sendmmsg: with a rate limit no more than fit one burst (at least one).
unsigned batch_size(double rate, size_t datagram)
{
    if (rate <= 0)
        return kBatch;
    return static_cast<unsigned>(std::clamp<double>(kBurstBytes / datagram, 1, kBatch));
}

} // namespace

Outcome UdpSender::create(const SendSpec &spec, const Options &options,
                          std::unique_ptr<SendStream> &out)
{
    Tap tap;
    if (Outcome o = open_tap(tap, spec.ring, spec.layout_hash, spec.message_size, LN_TAP_NEWEST);
        o.failed())
        return o;
    out = std::make_unique<UdpSender>(spec, options, std::move(tap));
    return outcome::ok();
}

UdpSender::UdpSender(const SendSpec &spec, const Options &options, Tap tap)
    : SendStream(spec), tap_(std::move(tap)), chunk_(static_cast<uint16_t>(options.udp_payload)),
      socket_buffer_(options.socket_buffer), spin_ns_(int64_t{options.spin_us} * 1000),
      rate_(options.udp_max_rate),
      batch_(batch_size(rate_, wire::kFragmentHeaderSize + chunk_ +
                                   sec::tag_bytes(sec::suite_for(spec.security)))),
      segments_(segments_per_send(wire::kFragmentHeaderSize + chunk_ +
                                  sec::tag_bytes(sec::suite_for(spec.security)))),
      suite_(sec::suite_for(spec.security)), tag_size_(sec::tag_bytes(suite_)),
      sample_(new uint8_t[spec.message_size ? spec.message_size : 1]),
      headers_(kBatch * wire::kFragmentHeaderSize), msgs_(kBatch), iov_(3 * kBatch),
      control_(kBatch)
{
    counters_.note_segment(ln_ring_tap_segment(tap_.get()));
    sec::stream_key(options.key, spec.token, static_cast<uint8_t>(spec.transport), stream_key_);
    if (suite_ == sec::Suite::chacha20poly1305 || suite_ == sec::Suite::aes256gcm)
        cipher_.reset(new uint8_t[spec.message_size ? spec.message_size : 1]);
    tags_.resize(kBatch * sec::kTagBytes);
    if (suite_ != sec::Suite::none)
        new_salt();
}

uint64_t UdpSender::fresh_salt() noexcept
{
    // Also greater than the last one of this process, should the clock step back.
    static std::atomic<uint64_t> last{0};
    timespec ts;
    ::clock_gettime(CLOCK_REALTIME, &ts);
    const uint64_t us =
        static_cast<uint64_t>(ts.tv_sec) * 1000000 + static_cast<uint64_t>(ts.tv_nsec) / 1000;
    uint64_t salt = us << 12 | (randombytes_random() & 0xfff);
    uint64_t prev = last.load(std::memory_order_relaxed);
    while (true) {
        uint64_t next = salt > prev ? salt : prev + 1;
        if (last.compare_exchange_weak(prev, next, std::memory_order_relaxed))
            return next;
    }
}

void UdpSender::new_salt()
{
    salt_ = fresh_salt();
    uint8_t raw[8];
    for (int i = 0; i < 8; ++i)
        raw[i] = static_cast<uint8_t>(salt_ >> (8 * i));
    Key k;
    sec::sub_key(stream_key_, "udp salt", raw, sizeof raw, k);
    box_ = std::make_unique<sec::Box>(k, suite_);
    counter_ = 0;
}

UdpSender::~UdpSender()
{
    stop();
    join();
}

void UdpSender::start()
{
    thread_ = std::thread([this] { run(); });
}

void UdpSender::stop() noexcept { stop_.raise(); }

void UdpSender::join() noexcept
{
    if (thread_.joinable())
        thread_.join();
}

void UdpSender::open_socket()
{
    auto now = std::chrono::steady_clock::now();
    if (now < next_open_)
        return;
    next_open_ = now + kResolveInterval;
    std::vector<Address> addresses;
    Outcome resolved = resolve(spec_.host, spec_.port, SOCK_DGRAM, addresses);
    std::string error = resolved.text;
    if (!resolved.failed()) {
        for (const Address &a : addresses) {
            UniqueFd fd(::socket(a.family(), SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0));
            if (fd && ::connect(fd.get(), a.get(), a.length) == 0) {
                set_buffer_sizes(fd.get(), socket_buffer_);
                sock_ = std::move(fd);
                reopen_ = false;
                return;
            }
            error = "cannot send to " + address_text(a.get()) + ": " + std::strerror(errno);
        }
    }
    counters_.set_error(error);
}

bool UdpSender::pace(size_t bytes)
{
    // A token bucket of kBurstBytes filled at rate_: a small sample finds it full and goes
    // at once; a large one is spread out so no receiver or switch buffer has to take it in
    // one burst.
    auto now = std::chrono::steady_clock::now();
    std::chrono::duration<double> elapsed = now - last_pace_;
    last_pace_ = now;
    credit_ = std::min(kBurstBytes, credit_ + elapsed.count() * rate_);
    credit_ -= static_cast<double>(bytes);
    if (credit_ >= 0)
        return true;
    return !stop_.sleep_us(static_cast<int64_t>(-credit_ / rate_ * 1e6));
}

UdpSender::Sent UdpSender::send_sample(uint64_t seq, int64_t timestamp_ns)
{
    if (reopen_)
        open_socket();
    if (!sock_)
        return Sent::failed;
    wire::Fragment f;
    f.token = spec_.token;
    f.seq = seq;
    f.timestamp_ns = timestamp_ns;
    f.sample_size = spec_.message_size;
    f.chunk_size = chunk_;
    f.count = static_cast<uint32_t>(wire::fragment_count(f.sample_size, chunk_));
    f.suite = static_cast<uint8_t>(suite_);
    if (box_ && counter_ + f.count > sec::kMaxCounter)
        new_salt(); // never in practice: 2^56 datagrams
    f.salt = salt_;
    uint8_t header[wire::kFragmentHeaderSize];
    wire::encode_fragment_header(header, f);
    const uint8_t *body = cipher_ ? cipher_.get() : sample_.get(); // what goes on the wire

    int refused = 0;
    int64_t backoff_us = kMinBackoffUs;
    for (uint32_t first = 0; first < f.count; first += batch_) {
        unsigned n = std::min<uint32_t>(batch_, f.count - first);
        if (rate_ > 0) {
            uint64_t offset = static_cast<uint64_t>(first) * chunk_;
            uint64_t payload = std::min<uint64_t>(uint64_t(n) * chunk_, f.sample_size - offset);
            if (!pace(n * (wire::kFragmentHeaderSize + tag_size_) + payload))
                return Sent::stopped;
        }
        for (unsigned i = 0; i < n; ++i) {
            uint32_t index = first + i;
            uint8_t *h = headers_.data() + i * wire::kFragmentHeaderSize;
            std::memcpy(h, header, sizeof header);
            wire::set_fragment_index(h, index);
            const uint64_t offset = static_cast<uint64_t>(index) * chunk_;
            const size_t length = wire::fragment_length(f.sample_size, chunk_, index);
            iov_[3 * i] = {h, wire::kFragmentHeaderSize};
            iov_[3 * i + 1] = {const_cast<uint8_t *>(body) + offset, length};
            iov_[3 * i + 2] = {tags_.data() + i * sec::kTagBytes, tag_size_};
            if (box_) { // every datagram a new counter, also one built again below
                wire::set_fragment_counter(h, f.suite, ++counter_);
                box_->seal(counter_, h, wire::kFragmentHeaderSize, sample_.get() + offset, length,
                           cipher_ ? cipher_.get() + offset : nullptr,
                           tags_.data() + i * sec::kTagBytes);
            }
        }
        // One message per datagram, or, with segmentation offload, per run of datagrams the
        // kernel cuts at the datagram size (all are that size but a sample's last one, which
        // can only end a run).
        unsigned count = 0;
        for (unsigned i = 0; i < n; ++count) {
            unsigned k = gso_ ? std::min(segments_, n - i) : 1;
            msgs_[count] = {};
            msghdr &m = msgs_[count].msg_hdr;
            m.msg_iov = &iov_[3 * i];
            m.msg_iovlen = 3 * k;
            if (k > 1) {
                m.msg_control = control_[count].data();
                m.msg_controllen = sizeof(control_[count]);
                cmsghdr *c = CMSG_FIRSTHDR(&m);
                c->cmsg_level = SOL_UDP;
                c->cmsg_type = UDP_SEGMENT;
                c->cmsg_len = CMSG_LEN(sizeof(uint16_t));
                uint16_t size =
                    static_cast<uint16_t>(wire::kFragmentHeaderSize + chunk_ + tag_size_);
                std::memcpy(CMSG_DATA(c), &size, sizeof size);
            }
            i += k;
        }
        for (unsigned done = 0; done < count;) {
            int sent = ::sendmmsg(sock_.get(), msgs_.data() + done, count - done, 0);
            if (sent > 0) {
                done += static_cast<unsigned>(sent);
                backoff_us = kMinBackoffUs;
                continue;
            }
            int err = errno;
            if (err == EINTR)
                continue;
            if (gso_ && done == 0 && (err == EINVAL || err == EIO || err == EOPNOTSUPP)) {
                gso_ = false;    // no segmentation offload on this path: one datagram per message
                first -= batch_; // (unsigned: the loop's step brings it back) the batch again
                break;
            }
            if (err == EAGAIN || err == EWOULDBLOCK) {
                // The socket buffer is full: the link is the limit, wait until it drains.
                if (wait_fd(sock_.get(), POLLOUT, stop_, -1) == Wait::stopped)
                    return Sent::stopped;
                continue;
            }
            if (err == ENOBUFS) {
                // The device queue is full; poll() would report writable at once, so back
                // off briefly instead.
                if (stop_.sleep_us(backoff_us))
                    return Sent::stopped;
                backoff_us = std::min(backoff_us * 2, kMaxBackoffUs);
                continue;
            }
            std::string text = "sending to " + spec_.host + ":" + std::to_string(spec_.port) +
                               ": " + std::strerror(err);
            if (err == ECONNREFUSED) {
                // An ICMP "port unreachable" for an earlier datagram; reading it cleared it,
                // and the receiver may be back (a daemon restart), so try again.
                counters_.set_error(text + " (nobody receives there)");
                if (++refused <= kRefusedRetries)
                    continue;
            } else {
                counters_.set_error(text);
            }
            reopen_ = true; // the address may have changed
            return Sent::failed;
        }
        if (stop_.raised())
            return Sent::stopped;
    }
    return Sent::ok;
}

void UdpSender::run()
{
    while (!stop_.raised()) {
        ln_sample_info info;
        Next next = next_sample(tap_.get(), sample_.get(), info, spin_ns_, stop_);
        if (next == Next::stop)
            break;
        if (next == Next::none)
            continue;
        switch (send_sample(info.seq, info.timestamp_ns)) {
        case Sent::ok:
            StreamCounters::add(counters_.samples);
            StreamCounters::add(counters_.bytes, spec_.message_size);
            break;
        case Sent::failed:
            StreamCounters::add(counters_.drops);
            break;
        case Sent::stopped:
            return;
        }
    }
}

} // namespace lnd::fwd
