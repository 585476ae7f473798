// The TCP receive threads (forward_tcp_recv.hpp).  A frame's size is checked against the
// stream before its payload is read, so a bad sender costs its connection, never memory.
// A large frame's payload is received straight into a ring slot while it arrives (the
// thread woken every 256 KiB or an eighth of the receive buffer, SO_RCVLOWAT), so the copy out of the socket overlaps the
// sending; a frame that stalls for 2 ms goes on through a private buffer, so the ring's
// write lock is never held for a stalled link.  A frame's trailer decides whether it is
// published (intact) or dropped (torn while sent), once its tag was found authentic (else
// the connection is closed and the frame counted as rejected).
#include "forward_tcp_recv.hpp"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <new>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <system_error>
#include <thread>
#include <vector>

#include "forward_wire.hpp"

namespace lnd::fwd {

namespace {

constexpr int kHelloTimeoutMs = 10000;
// Frames this large are received straight into a ring slot as their bytes arrive (the
// ring's write lock held meanwhile); smaller ones are read whole and then copied, which
// costs less than taking the lock early.
constexpr size_t kInPlaceBytes = 64 * 1024;
// While the lock is held, the thread sleeps until this much more of the frame is buffered
// (SO_RCVLOWAT), so a large frame costs a few wake-ups, not one per segment...
constexpr size_t kWakeBytes = 256 * 1024;
// ...and when nothing more came for this long, the frame goes on through a private buffer
// and the lock is let go (a local publisher of the topic waits at most this for a stalled
// link, plus the time a flowing frame takes to arrive).
constexpr int kStallMs = 2;
constexpr int kAcceptWakeMs = 1000; // to reap ended connections without new ones
// A sender host that died is noticed after about idle + interval * count seconds.
constexpr int kKeepIdle = 10, kKeepInterval = 2, kKeepCount = 3;

void send_reply(int fd, wire::Kind kind, wire::Reject reason, uint64_t token,
                const StopSignal &stop)
{
    uint8_t raw[wire::kReplySize];
    wire::encode_reply(raw, {kind, reason, token});
    iovec iov = {raw, sizeof raw};
    std::string error;
    write_full(fd, &iov, 1, stop, error);
}

// Wakes a reader only once `bytes` are buffered (SO_RCVLOWAT), unless the mark is that already.
void want_buffered(int fd, int &mark, size_t bytes)
{
    const int want = static_cast<int>(bytes);
    if (want != mark && ::setsockopt(fd, SOL_SOCKET, SO_RCVLOWAT, &want, sizeof want) == 0)
        mark = want;
}

// How much more of a frame wakes the connection: kWakeBytes, or an eighth of a smaller
// receive buffer (the sender's window may never let more than part of it be buffered).
size_t wake_bytes(int fd)
{
    int rcvbuf = 0;
    socklen_t len = sizeof rcvbuf;
    if (::getsockopt(fd, SOL_SOCKET, SO_RCVBUF, &rcvbuf, &len) != 0 || rcvbuf <= 0)
        return 1;
    return std::clamp<size_t>(static_cast<size_t>(rcvbuf) / 8, 1, kWakeBytes);
}

} // namespace

Io TcpReceiver::read_held(Connection &c, uint8_t *buf, size_t n, size_t &got, std::string &error,
                          TcpSession *feed)
{
    const int fd = c.fd.get();
    while (got < n) {
        size_t piece = 0;
        Io io = recv_some(fd, buf + got, n - got, piece, error);
        if (io == Io::ok) {
            if (feed) // its tag is computed while the rest arrives
                feed->part(buf + got, piece);
            got += piece;
            continue;
        }
        if (io != Io::timeout)
            return io;
        want_buffered(fd, c.mark, std::min(n - got, c.wake_bytes));
        switch (wait_fd(fd, POLLIN, stop_, kStallMs)) {
        case Wait::stopped:
            return Io::stopped;
        case Wait::timeout:
            return Io::timeout; // stalled: the caller lets go of the lock
        case Wait::ready:
            break;
        }
    }
    return Io::ok;
}

bool TcpReceiver::receive_frame(Connection &c, RecvStream &s, TcpSession &session, uint8_t *payload,
                                bool in_place)
{
    const int fd = c.fd.get();
    std::string error;
    uint8_t head[wire::kFrameHeaderSize];
    uint8_t tail[wire::kFrameTrailerSize + sec::kTagBytes];
    const size_t tail_size = wire::kFrameTrailerSize + session.tag_size();
    const uint8_t *tag = tail + wire::kFrameTrailerSize;
    want_buffered(fd, c.mark, 1);
    Io io = read_full(fd, head, sizeof head, stop_, -1, error, spin_ns_);
    if (io != Io::ok)
        return ended(c, s, io, error);
    wire::FrameHeader f;
    if (session.header(head, f) != TcpSession::Frame::intact) {
        StreamCounters::add(s.counters.invalid);
        s.counters.set_error("frame of " + std::to_string(f.size) + " bytes from " + c.peer +
                             ", the stream's messages have " + std::to_string(s.spec.message_size));
        return false;
    }
    size_t got = 0, tail_got = 0;
    void *slot = nullptr;
    if (in_place && s.begin(f.seq, &slot)) {
        // Straight into the slot as the bytes come; the slot stays unpublished until the
        // frame was judged.
        auto *dst = static_cast<uint8_t *>(slot);
        session.begin(head);
        io = read_held(c, dst, f.size, got, error, &session);
        if (io == Io::ok)
            io = read_held(c, tail, tail_size, tail_got, error);
        if (io == Io::ok) {
            const TcpSession::Frame v = session.frame(head, dst, tail, tag);
            s.finish(v == TcpSession::Frame::intact, f.timestamp_ns,
                     v == TcpSession::Frame::rejected);
            if (v == TcpSession::Frame::torn)
                return !s.closed(); // finish() counted the drop
            return judged(c, s, v);
        }
        if (io != Io::timeout) {
            s.finish(false, f.timestamp_ns); // counted as a drop
            return ended(c, s, io, error);
        }
        // Stalled: what came so far moves to the private buffer, the lock is let go.
        std::memcpy(payload, dst, got);
        s.finish(false, f.timestamp_ns, true);
    }
    want_buffered(fd, c.mark, 1);
    io = read_full(fd, payload + got, f.size - got, stop_, -1, error);
    if (io == Io::ok)
        io = read_full(fd, tail + tail_got, tail_size - tail_got, stop_, -1, error);
    if (io != Io::ok)
        return ended(c, s, io, error);
    TcpSession::Frame v = session.frame(head, payload, tail, tag);
    if (s.closed())
        return false;
    if (v == TcpSession::Frame::intact)
        s.write(payload, f.seq, f.timestamp_ns);
    return judged(c, s, v);
}

bool TcpReceiver::judged(const Connection &c, RecvStream &s, TcpSession::Frame verdict)
{
    switch (verdict) {
    case TcpSession::Frame::intact:
        return !s.closed();
    case TcpSession::Frame::torn:
        StreamCounters::add(s.counters.drops);
        return !s.closed();
    case TcpSession::Frame::rejected:
        s.reject("a frame from " + c.peer + " failed authentication; connection closed");
        return false;
    default:
        StreamCounters::add(s.counters.invalid);
        s.counters.set_error("a frame from " + c.peer + " does not end in a frame trailer");
        return false;
    }
}

bool TcpReceiver::ended(const Connection &c, RecvStream &s, Io io, const std::string &error)
{
    if (io == Io::error && !s.closed())
        s.counters.set_error("connection from " + c.peer + ": " + error);
    else if (io == Io::timeout && !s.closed())
        s.counters.set_error("connection from " + c.peer + ": a buffered frame did not arrive");
    return false;
}

TcpReceiver::TcpReceiver(int listener, RecvTable &table, TotalCounters &totals, unsigned spin_us)
    : listener_(listener), table_(table), totals_(totals), spin_ns_(int64_t{spin_us} * 1000)
{}

TcpReceiver::~TcpReceiver() { stop(); }

void TcpReceiver::start()
{
    acceptor_ = std::thread([this] { accept_loop(); });
}

void TcpReceiver::stop() noexcept
{
    stop_.raise();
    if (acceptor_.joinable())
        acceptor_.join();
    std::list<std::unique_ptr<Connection>> all;
    {
        std::lock_guard<std::mutex> lock(mutex_);
        all.swap(connections_);
    }
    for (auto &c : all)
        if (c->thread.joinable())
            c->thread.join(); // each watches stop_ in every wait
}

void TcpReceiver::drop_stream(uint64_t token) noexcept
{
    std::list<std::unique_ptr<Connection>> mine;
    {
        std::lock_guard<std::mutex> lock(mutex_);
        for (auto it = connections_.begin(); it != connections_.end();) {
            auto next = std::next(it);
            if ((*it)->token.load() == token) {
                ::shutdown((*it)->fd.get(), SHUT_RDWR); // wakes its thread's poll
                mine.splice(mine.end(), connections_, it);
            }
            it = next;
        }
    }
    for (auto &c : mine)
        if (c->thread.joinable())
            c->thread.join();
}

void TcpReceiver::reap()
{
    std::list<std::unique_ptr<Connection>> ended;
    {
        std::lock_guard<std::mutex> lock(mutex_);
        for (auto it = connections_.begin(); it != connections_.end();) {
            auto next = std::next(it);
            if ((*it)->done.load())
                ended.splice(ended.end(), connections_, it);
            it = next;
        }
    }
    for (auto &c : ended)
        if (c->thread.joinable())
            c->thread.join();
}

void TcpReceiver::accept_loop()
{
    while (!stop_.raised()) {
        Wait w = wait_fd(listener_, POLLIN, stop_, kAcceptWakeMs);
        reap();
        if (w == Wait::stopped)
            break;
        if (w == Wait::timeout)
            continue;
        Address from;
        from.length = sizeof from.storage;
        UniqueFd fd(::accept4(listener_, reinterpret_cast<sockaddr *>(&from.storage), &from.length,
                              SOCK_NONBLOCK | SOCK_CLOEXEC));
        if (!fd) {
            if (errno == EMFILE || errno == ENFILE || errno == ENOBUFS || errno == ENOMEM)
                stop_.sleep_for(100); // the connection stays pending: do not spin on it
            continue;
        }
        auto c = std::make_unique<Connection>();
        c->fd = std::move(fd);
        c->peer = address_text(from.get());
        int one = 1;
        ::setsockopt(c->fd.get(), IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
        ::setsockopt(c->fd.get(), SOL_SOCKET, SO_KEEPALIVE, &one, sizeof one);
        ::setsockopt(c->fd.get(), IPPROTO_TCP, TCP_KEEPIDLE, &kKeepIdle, sizeof kKeepIdle);
        ::setsockopt(c->fd.get(), IPPROTO_TCP, TCP_KEEPINTVL, &kKeepInterval, sizeof kKeepInterval);
        ::setsockopt(c->fd.get(), IPPROTO_TCP, TCP_KEEPCNT, &kKeepCount, sizeof kKeepCount);
        std::lock_guard<std::mutex> lock(mutex_);
        if (connections_.size() >= kMaxTcpConnections) {
            send_reply(c->fd.get(), wire::Kind::reject, wire::Reject::busy, 0, stop_);
            continue;
        }
        Connection &ref = *c;
        try {
            c->thread = std::thread([this, &ref] { serve(ref); });
        } catch (const std::system_error &) {
            continue; // no thread: the connection is closed, the sender retries
        }
        connections_.push_back(std::move(c));
    }
}

void TcpReceiver::serve(Connection &c)
{
    const int fd = c.fd.get();
    std::string error;
    uint8_t raw[wire::kHelloSize];
    wire::Hello hello;
    if (read_full(fd, raw, sizeof raw, stop_, kHelloTimeoutMs, error) != Io::ok) {
        c.done.store(true);
        return;
    }
    if (!wire::decode_hello(raw, hello)) {
        StreamCounters::add(totals_.malformed);
        c.done.store(true);
        return;
    }
    c.token.store(hello.token); // before the lookup: see drop_stream
    std::shared_ptr<RecvStream> s = table_.find(hello.token);
    if (!s || s->spec.transport != Transport::tcp) {
        StreamCounters::add(totals_.unknown_stream);
        send_reply(fd, wire::Kind::reject, wire::Reject::unknown_stream, hello.token, stop_);
        c.done.store(true);
        return;
    }
    TcpSession session;
    uint8_t nonce[wire::kHandshakeNonce];
    random_bytes(nonce, sizeof nonce);
    uint8_t reply[wire::kReplySize];
    HelloRules rules{s->spec.message_size, s->spec.layout_hash, s->spec.security, &s->key};
    wire::Reject refused = session.accept(hello, raw, rules, nonce, reply);
    if (refused != wire::Reject::none) {
        if (refused == wire::Reject::layout) {
            StreamCounters::add(s->counters.invalid);
            s->counters.set_error(c.peer + " sends messages of " +
                                  std::to_string(hello.message_size) +
                                  " bytes with another layout hash or size");
        } else {
            s->reject("connection from " + c.peer + " refused: " +
                      (refused == wire::Reject::key
                           ? "its hello is not authentic (another key?)"
                           : "its protection does not match the stream's security level " +
                                 std::string(sec::level_name(s->spec.security))));
        }
        send_reply(fd, wire::Kind::reject, refused, hello.token, stop_);
        c.done.store(true);
        return;
    }
    std::unique_ptr<uint8_t[]> payload(new (std::nothrow) uint8_t[s->spec.message_size]);
    if (!payload) {
        s->counters.set_error("no memory for a frame from " + c.peer);
        c.done.store(true);
        return; // closing tells the sender, which tries again later
    }
    iovec iov = {reply, sizeof reply};
    write_full(fd, &iov, 1, stop_, error);
    s->attach(c.peer);
    const bool in_place = s->spec.message_size >= kInPlaceBytes;
    c.wake_bytes = wake_bytes(fd);
    while (receive_frame(c, *s, session, payload.get(), in_place)) {
    }
    s->detach();
    c.done.store(true);
}

} // namespace lnd::fwd
