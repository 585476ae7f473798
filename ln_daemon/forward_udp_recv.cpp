// The UDP receive thread (forward_udp_recv.hpp).  Order of checks on a datagram: does it
// parse (else Totals.malformed), is its token a UDP stream here (else unknown_stream), does
// its tag authentic and its counter new (else the stream's rejected), does its geometry fit
// that stream (else the stream's invalid); only then is anything stored.
#include "forward_udp_recv.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <ctime>
#include <netinet/in.h>
#include <netinet/udp.h>
#include <sys/socket.h>
#include <thread>

namespace lnd::fwd {

namespace {

constexpr unsigned kBatch = 32; // datagrams per recvmmsg
// More than any UDP datagram over IPv4, and than what UDP_GRO coalesces into one.
constexpr size_t kBufferSize = 64 * 1024;
#ifndef UDP_GRO
#define UDP_GRO 104
#endif

// The size of the datagrams the kernel coalesced into this message (UDP_GRO), 0 if none.
size_t coalesced_size(msghdr &m)
{
    for (cmsghdr *c = CMSG_FIRSTHDR(&m); c; c = CMSG_NXTHDR(&m, c))
        if (c->cmsg_level == SOL_UDP && c->cmsg_type == UDP_GRO) {
            int size = 0;
            std::memcpy(&size, CMSG_DATA(c), sizeof size);
            return size > 0 ? static_cast<size_t>(size) : 0;
        }
    return 0;
}
constexpr int64_t kSweepNs = 100'000'000; // how often incomplete samples are checked for age

int64_t monotonic_ns() noexcept
{
    timespec ts;
    ::clock_gettime(CLOCK_MONOTONIC, &ts);
    return static_cast<int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

int64_t seconds_to_ns(double s) noexcept
{
    if (!(s > 0))
        return 0;
    if (s > 1e9)
        return INT64_MAX / 2;
    return static_cast<int64_t>(std::llround(s * 1e9));
}

} // namespace

UdpReceiver::UdpReceiver(int fd, RecvTable &table, TotalCounters &totals, const Options &options)
    : fd_(fd), table_(table), totals_(totals),
      max_idle_ns_(seconds_to_ns(options.udp_incomplete_timeout)),
      spin_ns_(int64_t{options.spin_us} * 1000)
{}

UdpReceiver::~UdpReceiver() { stop(); }

void UdpReceiver::start()
{
    thread_ = std::thread([this] { run(); });
}

void UdpReceiver::stop() noexcept
{
    stop_.store(true, std::memory_order_release);
    // On an unconnected UDP socket shutdown() fails with ENOTCONN but still marks the
    // receive side shut and wakes a blocked recvmmsg (which then returns 0); the socket's
    // receive timeout bounds the wait should it ever not.
    ::shutdown(fd_, SHUT_RD);
    if (thread_.joinable())
        thread_.join();
    cache_.clear();
}

RecvStream *UdpReceiver::lookup(uint64_t token)
{
    auto it = cache_.find(token);
    if (it != cache_.end())
        return it->second.get();
    std::shared_ptr<RecvStream> stream = table_.find(token);
    if (!stream || stream->spec.transport != Transport::udp)
        return nullptr;
    RecvStream *raw = stream.get();
    cache_.emplace(token, std::move(stream));
    return raw;
}

void UdpReceiver::sweep(int64_t now_ns)
{
    if (max_idle_ns_ <= 0)
        return;
    for (const std::shared_ptr<RecvStream> &s : table_.all()) {
        if (s->spec.transport != Transport::udp)
            continue;
        if (uint64_t n = s->reassembler.expire(now_ns, max_idle_ns_))
            StreamCounters::add(s->counters.drops, n);
    }
}

void UdpReceiver::handle(uint8_t *datagram, size_t size, const Address &from, int64_t now_ns)
{
    wire::Fragment f;
    if (!wire::decode_fragment(datagram, size, f)) {
        StreamCounters::add(totals_.malformed);
        return;
    }
    RecvStream *s = lookup(f.token);
    if (!s) {
        StreamCounters::add(totals_.unknown_stream);
        return;
    }
    if (const char *why = s->guard.admit(f, datagram)) {
        s->reject(std::string("datagram from ") + address_text(from.get()) + " rejected: " + why);
        return;
    }
    if (from.length != s->last_source.length ||
        std::memcmp(&from.storage, &s->last_source.storage, from.length) != 0) {
        s->last_source = from;
        s->counters.set_peer(address_text(from.get()));
    }
    if (const char *why = wire::check_fragment(f, s->spec.message_size)) {
        StreamCounters::add(s->counters.invalid);
        s->counters.set_error(std::string("invalid datagram from ") + address_text(from.get()) +
                              ": " + why);
        return;
    }
    if (f.count == 1) {
        s->write(f.data, f.seq, f.timestamp_ns);
        if (s->reassembler.in_progress())
            StreamCounters::add(s->counters.drops, s->reassembler.supersede(f.seq));
        return;
    }
    uint64_t newest = s->reassembler.active(f.seq) ? 0 : s->newest();
    Reassembler::Outcome o = s->reassembler.add(f, newest, now_ns);
    if (o.given_up)
        StreamCounters::add(s->counters.drops, o.given_up);
    switch (o.kind) {
    case Reassembler::Outcome::complete:
        s->write(o.data, f.seq, f.timestamp_ns);
        StreamCounters::add(s->counters.drops, s->reassembler.finish(f.seq));
        break;
    case Reassembler::Outcome::stale:
        StreamCounters::add(s->counters.stale);
        break;
    case Reassembler::Outcome::mismatch:
        StreamCounters::add(s->counters.invalid);
        s->counters.set_error("invalid datagram from " + address_text(from.get()) +
                              ": disagrees with earlier fragments of sample " +
                              std::to_string(f.seq));
        break;
    case Reassembler::Outcome::no_memory:
        s->counters.set_error("sample " + std::to_string(f.seq) + " of " +
                              std::to_string(f.sample_size) +
                              " bytes dropped: reassembly memory exhausted");
        break;
    case Reassembler::Outcome::pending:
    case Reassembler::Outcome::ignored:
    case Reassembler::Outcome::too_old:
        break;
    }
}

void UdpReceiver::run()
{
    std::unique_ptr<uint8_t[]> buffers(new uint8_t[kBatch * kBufferSize]);
    mmsghdr msgs[kBatch];
    iovec iov[kBatch];
    Address from[kBatch];
    alignas(cmsghdr) char control[kBatch][CMSG_SPACE(sizeof(int))];
    int one = 1; // datagrams of one flow may come coalesced: cut them apart below
    ::setsockopt(fd_, SOL_UDP, UDP_GRO, &one, sizeof one);
    int64_t next_sweep = monotonic_ns() + kSweepNs;
    while (!stop_.load(std::memory_order_acquire)) {
        for (unsigned i = 0; i < kBatch; ++i) {
            iov[i].iov_base = buffers.get() + i * kBufferSize;
            iov[i].iov_len = kBufferSize;
            std::memset(&msgs[i], 0, sizeof msgs[i]);
            msgs[i].msg_hdr.msg_name = &from[i].storage;
            msgs[i].msg_hdr.msg_namelen = sizeof from[i].storage;
            msgs[i].msg_hdr.msg_iov = &iov[i];
            msgs[i].msg_hdr.msg_iovlen = 1;
            msgs[i].msg_hdr.msg_control = control[i];
            msgs[i].msg_hdr.msg_controllen = sizeof control[i];
        }
        int n = -1;
        if (spin_ns_ > 0) { // a datagram that comes soon is taken without a wake-up
            for (int64_t end = monotonic_ns() + spin_ns_;
                 (n = ::recvmmsg(fd_, msgs, kBatch, MSG_DONTWAIT, nullptr)) < 0 &&
                 errno == EAGAIN && monotonic_ns() < end && !stop_.load(std::memory_order_acquire);)
                std::this_thread::yield();
        }
        if (n < 0)
            n = ::recvmmsg(fd_, msgs, kBatch, MSG_WAITFORONE, nullptr);
        int err = errno;
        int64_t now = monotonic_ns();
        if (table_.generation() != cache_generation_) {
            cache_.clear();
            cache_generation_ = table_.generation();
        }
        for (int i = 0; i < n; ++i) {
            if (msgs[i].msg_hdr.msg_flags & MSG_TRUNC) {
                StreamCounters::add(totals_.malformed);
                continue;
            }
            from[i].length = msgs[i].msg_hdr.msg_namelen;
            auto *data = static_cast<uint8_t *>(iov[i].iov_base);
            const size_t len = msgs[i].msg_len, step = coalesced_size(msgs[i].msg_hdr);
            if (step == 0) {
                handle(data, len, from[i], now);
                continue;
            }
            for (size_t at = 0; at < len; at += step)
                handle(data + at, std::min(step, len - at), from[i], now);
        }
        if (n < 0 && err != EAGAIN && err != EWOULDBLOCK && err != EINTR) {
            // Nothing on this socket fails for long (ENOMEM, a pending ICMP error): pause
            // briefly instead of spinning on the error.
            timespec pause = {0, 1'000'000};
            ::nanosleep(&pause, nullptr);
        }
        if (now >= next_sweep) {
            sweep(now);
            next_sweep = now + kSweepNs;
        }
    }
}

} // namespace lnd::fwd
