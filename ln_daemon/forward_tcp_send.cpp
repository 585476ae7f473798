// The TCP sending threads (forward_tcp_send.hpp).  Memory: at most capacity_ + 1 sample
// buffers ever exist (the queue with the sample in flight, plus the reader's), recycled
// between the two threads (a direct send by the reader sends from the ring slot and needs
// the reader's buffer only for what the socket did not take).  A
// sample counts as sent only once it was written whole; after a broken connection it is
// sent again from its first byte, so the receiver (which drops partial frames) sees it
// exactly once.  A frame the reader began stays first in the queue until the writer has
// finished it.  Samples that were in the kernel's buffers when a connection broke are
// lost without being counted.
#include "forward_tcp_send.hpp"

#include <algorithm>
#include <cassert>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <thread>

#include "forward_tcp_frame.hpp"
#include "forward_wire.hpp"

namespace lnd::fwd {

namespace {

// Samples this large are sent straight from their ring slot (borrowed; encrypt: enciphered
// from it); smaller ones are
// copied out first, which costs less than a separate send of their trailer.
constexpr uint64_t kBorrowBytes = 64 * 1024;

Outcome refused(std::string text)
{
    return outcome::error(proto::Err::stream_failed, std::move(text));
}

constexpr auto kIdleCheck = std::chrono::milliseconds(100); // peer-close check when idle
constexpr int kConnectTimeoutMs = 5000;
constexpr int kReplyTimeoutMs = 5000;
constexpr int kFirstBackoffMs = 50, kMaxBackoffMs = 2000;
constexpr unsigned kUserTimeoutMs = 10000; // unacknowledged data this long: connection dead
// A borrowed sample (not the newest) is skipped when the publisher would overwrite it within
// fewer than this many writes: it would most likely be torn on the wire.
constexpr uint64_t kHeadroom = 2;
// A large sample sent from its slot waits this long for room in the socket before it is
// copied and queued (a receiver that stopped reading then costs the queue's bound, counted).
constexpr auto kSendWait = std::chrono::milliseconds(200);

const char *reject_text(wire::Reject reason)
{
    switch (reason) {
    case wire::Reject::unknown_stream:
        return "the receiver has no TCP stream with this token";
    case wire::Reject::layout:
        return "the receiver's stream has another message size or layout";
    case wire::Reject::busy:
        return "the receiver has too many connections";
    case wire::Reject::security:
        return "the receiver's stream has another security level";
    case wire::Reject::key:
        return "the receiver did not accept this daemon's key (the key files differ)";
    default:
        return "the receiver refused the stream";
    }
}

// True (with `why`) if the peer closed or broke the connection; it sends nothing after its
// reply, so anything readable is the end.
bool peer_gone(int fd, std::string &why)
{
    char byte;
    ssize_t n = ::recv(fd, &byte, 1, MSG_PEEK | MSG_DONTWAIT);
    if (n == 0) {
        why = "closed by the receiver";
        return true;
    }
    if (n > 0) {
        why = "the receiver sent unexpected data";
        return true;
    }
    if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR)
        return false;
    why = std::strerror(errno);
    return true;
}

} // namespace

Outcome TcpSender::create(const SendSpec &spec, const Options &options,
                          std::unique_ptr<SendStream> &out)
{
    size_t size = spec.message_size ? spec.message_size : 1;
    size_t capacity = std::min(options.tcp_queue_samples, options.tcp_queue_bytes / size);
    if (capacity == 0)
        return outcome::error(proto::Err::stream_failed,
                              "a sample of " + std::to_string(spec.message_size) +
                                  " bytes does not fit the TCP queue bounds (" +
                                  std::to_string(options.tcp_queue_samples) + " samples, " +
                                  std::to_string(options.tcp_queue_bytes) + " bytes)");
    Tap tap;
    if (Outcome o = open_tap(tap, spec.ring, spec.layout_hash, spec.message_size, LN_TAP_EVERY);
        o.failed())
        return o;
    out = std::make_unique<TcpSender>(spec, options, std::move(tap), capacity);
    return outcome::ok();
}

TcpSender::TcpSender(const SendSpec &spec, const Options &options, Tap tap, size_t capacity)
    : SendStream(spec), tap_(std::move(tap)), capacity_(capacity),
      socket_buffer_(options.socket_buffer), spin_ns_(int64_t{options.spin_us} * 1000),
      suite_(sec::suite_for(spec.security))
{
    counters_.note_segment(ln_ring_tap_segment(tap_.get()));
    sec::stream_key(options.key, spec.token, static_cast<uint8_t>(spec.transport), stream_key_);
    if (suite_ == sec::Suite::chacha20poly1305 || suite_ == sec::Suite::aes256gcm)
        cipher_.reset(new uint8_t[spec.message_size ? spec.message_size : 1]);
}

const uint8_t *TcpSender::seal(const Sample &s, const uint8_t *header, const uint8_t *trailer,
                               const uint8_t *plain)
{
    if (!box_)
        return plain;
    if (s.sent == 0) // the frame's counter: counter_ counts the frames written whole
        box_->seal(counter_ + 1, header, wire::kFrameHeaderSize, plain,
                   tagged_payload(s.intact, spec_.message_size), cipher_.get(), tag_, trailer,
                   wire::kFrameTrailerSize);
    return cipher_ ? cipher_.get() : plain;
}

TcpSender::~TcpSender()
{
    stop();
    join();
}

void TcpSender::start()
{
    reader_ = std::thread([this] { read_loop(); });
    try {
        writer_ = std::thread([this] { write_loop(); });
    } catch (...) {
        stop();
        join();
        throw;
    }
}

void TcpSender::stop() noexcept
{
    stop_.raise();
    std::lock_guard<std::mutex> lock(mutex_);
    ready_.notify_all();
}

void TcpSender::join() noexcept
{
    if (reader_.joinable())
        reader_.join();
    if (writer_.joinable())
        writer_.join();
}

TcpSender::Buffer TcpSender::take_buffer()
{
    {
        std::lock_guard<std::mutex> lock(mutex_);
        if (!free_.empty()) {
            Buffer b = std::move(free_.back());
            free_.pop_back();
            return b;
        }
        // Every buffer not free is queued, in flight or the reader's, so with none free
        // fewer than capacity_ + 1 exist.
        ++allocated_;
        assert(allocated_ <= capacity_ + 1);
    }
    return Buffer(new uint8_t[spec_.message_size ? spec_.message_size : 1]);
}

void TcpSender::give_buffer(Buffer b) { free_.push_back(std::move(b)); }

void TcpSender::read_loop()
{
    Buffer buf = take_buffer();
    const bool borrow = spec_.message_size >= kBorrowBytes;
    while (!stop_.raised()) {
        ln_sample_info info;
        const void *payload = nullptr;
        Next next = borrow ? next_borrowed(tap_.get(), &payload, info, spin_ns_, stop_)
                           : next_sample(tap_.get(), buf.get(), info, spin_ns_, stop_);
        if (next == Next::stop)
            break;
        if (next == Next::none)
            continue;
        if (borrow && about_to_go(info.seq)) {
            // Sending the oldest sample of a stream a whole ring behind would tear it: skip
            // to newer ones (the drop is counted), so the stream catches up.
            ln_ring_tap_release(tap_.get());
            StreamCounters::add(counters_.drops);
            continue;
        }
        if (send_direct(borrow ? payload : nullptr, buf, info)) {
            if (!buf)
                buf = take_buffer();
            continue;
        }
        if (borrow) {
            std::memcpy(buf.get(), payload, spec_.message_size);
            if (ln_ring_tap_release(tap_.get()) != LN_OK) {
                StreamCounters::add(counters_.drops); // overwritten while copied
                continue;
            }
        }
        bool queued = false;
        {
            std::lock_guard<std::mutex> lock(mutex_);
            if (queue_.size() + in_flight_ >= capacity_) {
                auto victim = queue_.begin();
                if (victim != queue_.end() && victim->sent > 0)
                    ++victim; // its frame is partly on the wire: it must be finished
                if (victim != queue_.end()) {
                    give_buffer(std::move(victim->data));
                    queue_.erase(victim);
                    StreamCounters::add(counters_.drops);
                }
            }
            if (queue_.size() + in_flight_ < capacity_) {
                queue_.push_back(Sample{info.seq, info.timestamp_ns, std::move(buf)});
                queued = true;
            }
            queued_.store(queue_.size(), std::memory_order_release);
            if (!queued)
                StreamCounters::add(counters_.drops); // what is being sent fills the queue
        }
        if (queued) {
            ready_.notify_one();
            buf = take_buffer();
        }
    }
}

bool TcpSender::about_to_go(uint64_t seq)
{
    const uint64_t newest = ln_ring_tap_write_seq(tap_.get());
    const uint64_t slots = ln_ring_tap_slots(tap_.get());
    if (newest <= seq || slots == 0)
        return false; // the newest is always sent
    const uint64_t lag = newest - seq;
    return lag + 1 + kHeadroom > slots; // fewer than kHeadroom writes until it is overwritten
}

size_t TcpSender::frame_size() const noexcept
{
    return wire::kFrameHeaderSize + spec_.message_size + wire::kFrameTrailerSize +
           sec::tag_bytes(suite_);
}

void TcpSender::count_sent(const Sample &s)
{
    if (!s.intact) {
        StreamCounters::add(counters_.drops);
        return;
    }
    StreamCounters::add(counters_.samples);
    StreamCounters::add(counters_.bytes, spec_.message_size);
}

bool TcpSender::send_direct(const void *borrowed, Buffer &buf, const ln_sample_info &info)
{
    int fd;
    {
        std::lock_guard<std::mutex> lock(mutex_);
        if (!writer_idle_ || reader_sending_ || in_flight_ || !queue_.empty())
            return false;
        reader_sending_ = true;
        in_flight_ = true;
        fd = sock_.get();
    }
    Sample s{info.seq, info.timestamp_ns, nullptr};
    const auto *slot = static_cast<const uint8_t *>(borrowed);
    const uint8_t *payload = slot ? slot : buf.get();
    uint8_t header[wire::kFrameHeaderSize];
    uint8_t trailer[wire::kFrameTrailerSize];
    wire::encode_frame_header(header, {s.seq, s.timestamp_ns, spec_.message_size});
    wire::encode_frame_trailer(trailer, true);
    if (!slot || cipher_) // sealed once, before any byte goes (encrypt: from the slot itself)
        payload = seal(s, header, trailer, payload);
    // Sends the frame up to `end`; `wait`: while the socket is full, waits for room until
    // `deadline` (a stop or an error ends it early; the writer meets and handles the error).
    using Clock = std::chrono::steady_clock;
    const Clock::time_point deadline = Clock::now() + kSendWait;
    auto send_part = [&](size_t end, bool wait) {
        while (s.sent < end) {
            iovec iov[4];
            msghdr msg = {};
            msg.msg_iov = iov;
            msg.msg_iovlen = frame_iov(header, trailer, payload, s, iov);
            if (end < frame_size()) // header and payload only: not the trailer nor the tag
                msg.msg_iovlen -= box_ ? 2 : 1;
            ssize_t n = ::sendmsg(fd, &msg, MSG_NOSIGNAL | MSG_DONTWAIT);
            if (n > 0) {
                s.sent += static_cast<size_t>(n);
                continue;
            }
            if (n < 0 && errno == EINTR)
                continue;
            if (!wait || n == 0 || (errno != EAGAIN && errno != EWOULDBLOCK))
                break;
            auto left =
                std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
            if (left.count() <= 0 ||
                wait_fd(fd, POLLOUT, stop_, static_cast<int>(left.count())) != Wait::ready)
                break;
        }
    };
    if (slot) {
        // Header and payload straight from the slot (encrypt: enciphered from it), waiting
        // a while for room in the socket rather than copying (the ring is the queue: the
        // publisher overwrites the slot only when the stream falls a whole ring behind;
        // after kSendWait what is left goes to the queue, copied), then whether
        // it stayed intact meanwhile, then the trailer that says so.  authenticate: the tag
        // is taken over the slot while it is still borrowed, so if it stayed intact the bytes
        // sent are the bytes tagged (encrypt: the bytes enciphered); a torn frame's tag
        // covers header and trailer only.
        const size_t body = wire::kFrameHeaderSize + spec_.message_size;
        send_part(body, true);
        s.whole = s.sent < body; // the writer finishes it (or sends it again) from a copy
        if (s.whole)
            std::memcpy(buf.get(), slot, spec_.message_size);
        if (box_ && !cipher_)
            box_->seal(counter_ + 1, header, wire::kFrameHeaderSize, slot, spec_.message_size,
                       nullptr, tag_, trailer, wire::kFrameTrailerSize);
        s.intact = ln_ring_tap_release(tap_.get()) == LN_OK;
        wire::encode_frame_trailer(trailer, s.intact);
        if (box_ && !s.intact)
            box_->seal(counter_ + 1, header, wire::kFrameHeaderSize, nullptr, 0, nullptr, tag_,
                       trailer, wire::kFrameTrailerSize);
        if (s.sent == body)
            send_part(frame_size(), true);
    } else {
        send_part(frame_size(), false); // a copy: the whole frame in one go, else queued
    }
    const bool whole = s.sent == frame_size();
    if (whole)
        ++counter_; // still the reader's: reader_sending_ is cleared below
    const bool queue = !whole && (s.sent > 0 || s.intact); // a torn frame not begun is dropped
    {
        std::lock_guard<std::mutex> lock(mutex_);
        reader_sending_ = false;
        in_flight_ = false;
        if (queue) {
            s.data = std::move(buf);
            queue_.push_front(std::move(s)); // the queue was empty: nothing overtakes it
            queued_.store(queue_.size(), std::memory_order_release);
        }
    }
    if (queue)
        ready_.notify_one();
    else if (whole)
        count_sent(s);
    else
        StreamCounters::add(counters_.drops);
    return true;
}

size_t TcpSender::frame_iov(uint8_t *header, uint8_t *trailer, const uint8_t *payload,
                            const Sample &s, iovec iov[4]) const
{
    const size_t h = wire::kFrameHeaderSize, body = h + spec_.message_size;
    const size_t end = body + wire::kFrameTrailerSize;
    size_t count = 0, at = s.sent;
    if (at < h) {
        iov[count++] = {header + at, h - at};
        at = h;
    }
    if (at < body) {
        iov[count++] = {const_cast<uint8_t *>(payload) + (at - h), body - at};
        at = body;
    }
    if (at < end) {
        iov[count++] = {trailer + (at - body), end - at};
        at = end;
    }
    if (box_)
        iov[count++] = {const_cast<uint8_t *>(tag_) + (at - end), sec::kTagBytes - (at - end)};
    return count;
}

Io TcpSender::write_sample(Sample &s, std::string &error)
{
    uint8_t header[wire::kFrameHeaderSize];
    uint8_t trailer[wire::kFrameTrailerSize];
    wire::encode_frame_header(header, {s.seq, s.timestamp_ns, spec_.message_size});
    wire::encode_frame_trailer(trailer, s.intact);
    const uint8_t *payload = seal(s, header, trailer, s.data.get());
    iovec iov[4];
    size_t count = frame_iov(header, trailer, payload, s, iov);
    return write_full(sock_.get(), iov, static_cast<int>(count), stop_, error);
}

Outcome TcpSender::try_connect()
{
    std::vector<Address> addresses;
    if (Outcome o = resolve(spec_.host, spec_.port, SOCK_STREAM, addresses); o.failed())
        return o;
    std::string error;
    UniqueFd fd;
    for (const Address &a : addresses) {
        std::string where = "connecting to " + address_text(a.get()) + ": ";
        fd.reset(::socket(a.family(), SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0));
        if (!fd) {
            error = where + std::strerror(errno);
            continue;
        }
        int one = 1;
        ::setsockopt(fd.get(), IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
        ::setsockopt(fd.get(), IPPROTO_TCP, TCP_USER_TIMEOUT, &kUserTimeoutMs,
                     sizeof kUserTimeoutMs);
        set_buffer_sizes(fd.get(), socket_buffer_);
        if (::connect(fd.get(), a.get(), a.length) != 0 && errno != EINPROGRESS) {
            error = where + std::strerror(errno);
            fd.reset();
            continue;
        }
        Wait w = wait_fd(fd.get(), POLLOUT, stop_, kConnectTimeoutMs);
        if (w == Wait::stopped)
            return refused("stopped");
        int soerr = 0;
        socklen_t len = sizeof soerr;
        if (w == Wait::timeout)
            soerr = ETIMEDOUT;
        else if (::getsockopt(fd.get(), SOL_SOCKET, SO_ERROR, &soerr, &len) != 0)
            soerr = errno;
        if (soerr != 0) {
            error = where + std::strerror(soerr);
            fd.reset();
            continue;
        }
        break;
    }
    if (!fd)
        return refused(error);

    uint8_t nonce[wire::kHandshakeNonce];
    random_bytes(nonce, sizeof nonce);
    uint8_t hello[wire::kHelloSize];
    encode_tcp_hello(spec_, stream_key_, suite_, nonce, hello);
    iovec iov = {hello, sizeof hello};
    std::string io_error;
    Io io = write_full(fd.get(), &iov, 1, stop_, io_error);
    if (io == Io::ok) {
        uint8_t raw[wire::kReplySize];
        io = read_full(fd.get(), raw, sizeof raw, stop_, kReplyTimeoutMs, io_error);
        if (io == Io::ok) {
            wire::Reply reply;
            if (!wire::decode_reply(raw, reply))
                return refused("the receiver's reply is not one of this protocol version");
            if (reply.kind == wire::Kind::reject) // a busy receiver rejects before the hello
                return refused(reject_text(reply.reason));
            if (reply.token != spec_.token)
                return refused("the receiver accepted another stream");
            if (!check_tcp_reply(hello, reply, raw, stream_key_, suite_, box_))
                return refused("the receiver's accept is not authentic (the key files differ?)");
            counter_ = 0;
            sock_ = std::move(fd);
            return outcome::ok();
        }
    }
    switch (io) {
    case Io::closed:
        return refused("the receiver closed the connection during the hello");
    case Io::timeout:
        return refused("no reply from the receiver");
    case Io::stopped:
        return refused("stopped");
    default:
        return refused("hello: " + io_error);
    }
}

bool TcpSender::connect_with_backoff()
{
    int backoff_ms = kFirstBackoffMs;
    while (!stop_.raised()) {
        Outcome connected = try_connect();
        if (!connected.failed()) {
            counters_.set_connected(true);
            return true;
        }
        if (stop_.raised())
            break;
        counters_.set_error(spec_.host + ":" + std::to_string(spec_.port) + ": " + connected.text);
        if (stop_.sleep_for(backoff_ms))
            break;
        backoff_ms = std::min(backoff_ms * 2, kMaxBackoffMs);
    }
    return false;
}

void TcpSender::lost(const std::string &why)
{
    sock_.reset();
    // The reason first: whoever sees the stream disconnected also sees why.
    counters_.set_error("connection to " + spec_.host + ":" + std::to_string(spec_.port) +
                        " lost: " + why);
    counters_.set_connected(false);
}

void TcpSender::write_loop()
{
    Sample current;
    bool have = false;
    while (!stop_.raised()) {
        if (!sock_ && !connect_with_backoff())
            break;
        if (!have) {
            for (auto end = std::chrono::steady_clock::now() + std::chrono::nanoseconds(spin_ns_);
                 spin_ns_ > 0 && queued_.load(std::memory_order_acquire) == 0 && !stop_.raised() &&
                 std::chrono::steady_clock::now() < end;)
                std::this_thread::yield(); // a sample that comes soon: no wake-up
            std::unique_lock<std::mutex> lock(mutex_);
            writer_idle_ = true; // from here the reader may send on sock_ itself
            ready_.wait_for(lock, kIdleCheck, [this] { return stop_.raised() || !queue_.empty(); });
            writer_idle_ = false;
            if (stop_.raised())
                break;
            if (queue_.empty()) {
                if (reader_sending_)
                    continue; // the connection is busy, so not idle: check it later
                lock.unlock();
                std::string why;
                if (peer_gone(sock_.get(), why))
                    lost(why);
                continue;
            }
            current = std::move(queue_.front());
            queue_.pop_front();
            queued_.store(queue_.size(), std::memory_order_release);
            in_flight_ = true;
            have = true;
        }
        std::string error;
        const Io io = write_sample(current, error);
        switch (io) {
        case Io::ok: {
            ++counter_;
            count_sent(current);
            std::lock_guard<std::mutex> lock(mutex_);
            give_buffer(std::move(current.data));
            in_flight_ = false;
            have = false;
            break;
        }
        case Io::stopped:
            return;
        default:
            lost(io == Io::closed ? "closed by the receiver" : error);
            current.sent = 0; // the receiver drops a partial frame: send it whole again
            // unless it was torn, or was sent from the slot and is not here: then it is gone
            if (!current.intact || !current.whole) {
                StreamCounters::add(counters_.drops);
                std::lock_guard<std::mutex> lock(mutex_);
                give_buffer(std::move(current.data));
                in_flight_ = false;
                have = false;
            }
            break;
        }
    }
}

} // namespace lnd::fwd
