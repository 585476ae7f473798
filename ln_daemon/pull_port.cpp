// The UDP side of pull topics (pull_port.hpp): binding, the receive thread, decoding,
// routing by longest name prefix and the per-port counters.  The reply rules themselves
// are the topic's (PullTopic::answer).
#include "pull_port.hpp"

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cstring>
#include <netdb.h>
#include <poll.h>
#include <sys/prctl.h>
#include <sys/socket.h>

#include "log.hpp"

namespace lnd {

namespace {

// What follows a topic's name in an Interest: "sync" (and anything after it), or one
// SequenceNum component.  False for anything else.
bool parse_suffix(ln_ndn_bytes rest, PullInterest &in) noexcept
{
    ln_ndn_component c;
    if (ln_ndn_name_next(&rest, &c) != 1)
        return false;
    if (c.type == LN_NDN_T_GENERIC && c.value.size == 4 &&
        std::memcmp(c.value.data, "sync", 4) == 0) {
        in.sync = true;
        return true;
    }
    if (c.type != LN_NDN_T_SEQUENCE_NUM || ln_ndn_read_nonneg(c.value, &in.seq) != LN_NDN_OK)
        return false;
    ln_ndn_component more;
    return ln_ndn_name_next(&rest, &more) == 0;
}

} // namespace

Outcome PullPort::open(const std::string &address, uint16_t port, std::unique_ptr<PullPort> &out)
{
    const std::string host = address.empty() ? "0.0.0.0" : address;
    const std::string where = host + ":" + std::to_string(port);
    addrinfo hints = {};
    hints.ai_family = AF_UNSPEC;
    hints.ai_socktype = SOCK_DGRAM;
    hints.ai_flags = AI_NUMERICHOST | AI_NUMERICSERV | AI_PASSIVE;
    addrinfo *res = nullptr;
    int rc = ::getaddrinfo(host.c_str(), std::to_string(port).c_str(), &hints, &res);
    if (rc != 0 || !res)
        return outcome::error(proto::Err::pull_failed,
                              "pull address '" + host +
                                  "' is not a numeric IPv4 or IPv6 address (" + ::gai_strerror(rc) +
                                  ")");
    UniqueFd fd(::socket(res->ai_family, SOCK_DGRAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0));
    if (!fd) {
        int socket_errno = errno;
        ::freeaddrinfo(res);
        return outcome::error(proto::Err::pull_failed, "cannot make a UDP socket for " + where +
                                                           ": " + std::strerror(socket_errno));
    }
    rc = ::bind(fd.get(), res->ai_addr, res->ai_addrlen);
    int bind_errno = errno;
    ::freeaddrinfo(res);
    if (rc != 0)
        return outcome::error(
            proto::Err::pull_failed,
            "cannot bind UDP " + where + ": " + std::strerror(bind_errno) +
                (bind_errno == EADDRINUSE ? " (something else uses that port)" : ""));
    sockaddr_storage bound{};
    socklen_t len = sizeof bound;
    ::getsockname(fd.get(), reinterpret_cast<sockaddr *>(&bound), &len);
    uint16_t real = bound.ss_family == AF_INET6
                        ? ntohs(reinterpret_cast<sockaddr_in6 *>(&bound)->sin6_port)
                        : ntohs(reinterpret_cast<sockaddr_in *>(&bound)->sin_port);
    std::unique_ptr<PullPort> p(new PullPort(host, real, std::move(fd)));
    p->thread_ = std::thread([raw = p.get()] { raw->loop(); });
    out = std::move(p);
    return outcome::ok();
}

PullPort::PullPort(std::string address, uint16_t port, UniqueFd fd)
    : address_(std::move(address)), port_(port), fd_(std::move(fd)), rx_(kPullRxBytes),
      sender_(kMaxPullMessage, kPullRxBytes)
{
    sender_.set_fd(fd_.get());
}

PullPort::~PullPort()
{
    stop_.raise();
    if (thread_.joinable())
        thread_.join();
}

void PullPort::attach(PullTopic *topic)
{
    std::lock_guard<std::mutex> lock(mutex_);
    entries_.push_back({topic->config().name, topic});
}

void PullPort::detach(PullTopic *topic)
{
    std::lock_guard<std::mutex> lock(mutex_);
    entries_.erase(std::remove_if(entries_.begin(), entries_.end(),
                                  [topic](const Entry &e) { return e.topic == topic; }),
                   entries_.end());
}

const PullTopic *PullPort::serving(const std::vector<uint8_t> &name, const PullTopic *except) const
{
    std::lock_guard<std::mutex> lock(mutex_);
    for (const Entry &e : entries_)
        if (e.topic != except && e.name == name)
            return e.topic;
    return nullptr;
}

size_t PullPort::topics() const
{
    std::lock_guard<std::mutex> lock(mutex_);
    return entries_.size();
}

PullPortStatus PullPort::status() const
{
    PullPortStatus s;
    s.address = address_;
    s.port = port_;
    std::lock_guard<std::mutex> lock(stats_mutex_);
    s.counters = counters_;
    s.last_error = error_.text;
    return s;
}

void PullPort::count(uint64_t PullPortCounters::*which) noexcept
{
    std::lock_guard<std::mutex> lock(stats_mutex_);
    ++(counters_.*which);
}

void PullPort::set_error(const ErrorText &e) noexcept
{
    bool changed;
    {
        std::lock_guard<std::mutex> lock(stats_mutex_);
        changed = error_.set("%s", e.text);
    }
    if (changed)
        logf("pull port %s:%u: %s", address_.c_str(), port_, e.text);
}

const PullPort::Entry *PullPort::route(ln_ndn_bytes name) const noexcept
{
    const Entry *best = nullptr;
    for (const Entry &e : entries_)
        if ((!best || e.name.size() > best->name.size()) &&
            ln_ndn_name_has_prefix(name, {e.name.data(), e.name.size()}) == 1)
            best = &e;
    return best;
}

void PullPort::receive(const uint8_t *buf, size_t size, const PullPeer &from)
{
    ln_ndn_packet pkt;
    if (ln_ndn_decode(buf, size, &pkt) != LN_NDN_OK || pkt.pit_token.size > kMaxPitToken)
        return count(&PullPortCounters::bad);
    if (pkt.type != LN_NDN_T_INTEREST || pkt.lp_nack)
        return count(&PullPortCounters::other);
    PullInterest in;
    in.name = pkt.interest.name;
    in.has_nonce = pkt.interest.has_nonce;
    in.nonce = pkt.interest.nonce;
    in.lifetime_ms = pkt.interest.lifetime_ms;
    in.peer = from;
    in.peer.token_size = static_cast<uint8_t>(pkt.pit_token.size);
    if (pkt.pit_token.size)
        std::memcpy(in.peer.token, pkt.pit_token.data, pkt.pit_token.size);
    std::lock_guard<std::mutex> lock(mutex_);
    const Entry *e = route(in.name);
    if (!e || !parse_suffix({in.name.data + e->name.size(), in.name.size - e->name.size()}, in))
        return count(&PullPortCounters::unknown);
    in.name_hash = PullTopic::hash_name(in.name);
    ErrorText problem;
    if (!e->topic->answer(in, PullTopic::now(), sender_, problem))
        set_error(problem);
}

void PullPort::loop()
{
    ::prctl(PR_SET_NAME, "ln_pull_port");
    ::prctl(PR_SET_TIMERSLACK, 1000UL); // parked Interests expire on time
    pollfd fds[2] = {{fd_.get(), POLLIN, 0}, {stop_.fd(), POLLIN, 0}};
    PullTopic::Nanos next = INT64_MAX; // the earliest expiry of a parked Interest
    while (!stop_.raised()) {
        int timeout = kPullIdlePollMs;
        if (next != INT64_MAX) {
            PullTopic::Nanos wait = next - PullTopic::now();
            timeout = wait <= 0 ? 0
                                : static_cast<int>(std::min<PullTopic::Nanos>(
                                      (wait + 999999) / 1000000, kPullIdlePollMs));
        }
        int rc = ::poll(fds, 2, timeout);
        if (rc < 0 && errno != EINTR) {
            ErrorText e;
            e.set("poll: %s", std::strerror(errno));
            set_error(e);
            stop_.sleep_us(100000);
        }
        for (int i = 0; rc > 0 && (fds[0].revents & POLLIN) && i < kPullBatch; ++i) {
            PullPeer from;
            socklen_t len = sizeof from.addr;
            ssize_t n = ::recvfrom(fd_.get(), rx_.data(), rx_.size(), MSG_TRUNC,
                                   reinterpret_cast<sockaddr *>(&from.addr), &len);
            if (n < 0) {
                if (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) {
                    ErrorText e;
                    e.set("recvfrom: %s", std::strerror(errno));
                    set_error(e);
                }
                break;
            }
            from.addr_len = len;
            count(&PullPortCounters::packets);
            if (static_cast<size_t>(n) > rx_.size()) // cut off: MSG_TRUNC gave the real size
                count(&PullPortCounters::bad);
            else
                receive(rx_.data(), static_cast<size_t>(n), from);
        }
        PullTopic::Nanos now = PullTopic::now();
        next = INT64_MAX;
        std::lock_guard<std::mutex> lock(mutex_);
        for (const Entry &e : entries_)
            next = std::min(next, e.topic->expire(now));
    }
}

} // namespace lnd
