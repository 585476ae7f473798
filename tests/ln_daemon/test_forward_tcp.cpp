// End-to-end tests of TCP forwarding on 127.0.0.1: every sample arrives in order; a
// receiver that never answers or stops reading costs only queue drops, within the queue
// bound; a receiving Forwarder that goes away and comes back on the same port gets the
// stream again; hellos and frames that are wrong are refused and counted.
#include <atomic>
#include <cerrno>
#include <cstdio>
#include <memory>
#include <netinet/tcp.h>
#include <thread>
#include <vector>

#include "forward_test.hpp"
#include "forward_wire.hpp"

using namespace fwdtest;
using lnd::fwd::Forwarder;
using lnd::fwd::Level;
using lnd::fwd::Options;
using lnd::fwd::Transport;
namespace wire = lnd::fwd::wire;

namespace {

constexpr uint64_t kToken = 0x5555666677778888ull;

// A TCP listener on 127.0.0.1 with a tiny receive buffer; with `answer` a thread accepts one
// connection, reads the hello and accepts the stream, then never reads again.
class StuckReceiver {
public:
    explicit StuckReceiver(bool answer) : fd_(::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0))
    {
        int small = 4096;
        ::setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &small, sizeof small);
        sockaddr_in a = loopback(0);
        LN_CHECK_EQ(::bind(fd_, reinterpret_cast<sockaddr *>(&a), sizeof a), 0);
        LN_CHECK_EQ(::listen(fd_, 4), 0);
        if (answer)
            thread_ = std::thread([this] { serve(); });
    }
    ~StuckReceiver()
    {
        ::shutdown(fd_, SHUT_RDWR); // ends a pending accept
        if (thread_.joinable())
            thread_.join();
        if (conn_ >= 0)
            ::close(conn_);
        ::close(fd_);
    }
    uint16_t port() const { return local_port(fd_); }

private:
    void serve()
    {
        conn_ = ::accept(fd_, nullptr, nullptr);
        if (conn_ < 0)
            return;
        uint8_t hello[wire::kHelloSize];
        if (::recv(conn_, hello, sizeof hello, MSG_WAITALL) != sizeof hello)
            return;
        wire::Hello h;
        LN_CHECK(wire::decode_hello(hello, h));
        uint8_t reply[wire::kReplySize];
        wire::encode_reply(reply, {wire::Kind::accept, wire::Reject::none, h.token});
        LN_CHECK_EQ(::send(conn_, reply, sizeof reply, MSG_NOSIGNAL), sizeof reply);
    }

    int fd_;
    int conn_ = -1;
    std::thread thread_;
};

// A plain TCP client of a receiving Forwarder, for hand-made hellos and frames.
class Client {
public:
    explicit Client(uint16_t port) : fd_(::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0))
    {
        sockaddr_in a = loopback(port);
        LN_CHECK_EQ(::connect(fd_, reinterpret_cast<sockaddr *>(&a), sizeof a), 0);
    }
    ~Client() { ::close(fd_); }
    void send(const void *p, size_t n)
    {
        LN_CHECK_EQ(::send(fd_, p, n, MSG_NOSIGNAL), static_cast<ssize_t>(n));
    }
    // The reply, or kind hello (never sent by a receiver) if the connection ended.
    wire::Reply reply()
    {
        uint8_t raw[wire::kReplySize];
        wire::Reply r;
        r.kind = wire::Kind::hello;
        if (::recv(fd_, raw, sizeof raw, MSG_WAITALL) == sizeof raw)
            LN_CHECK(wire::decode_reply(raw, r));
        return r;
    }
    // True once the receiver closed the connection (a reset if it left bytes unread).
    bool closed_by_peer()
    {
        char byte;
        ssize_t n = ::recv(fd_, &byte, 1, 0);
        return n == 0 || (n < 0 && errno == ECONNRESET);
    }

private:
    int fd_;
};

// Stream kToken from `src` (tx) to `dst` (rx) over TCP, connected.
void connect_tcp(Forwarder &rx, Forwarder &tx, const TestRing &src, const TestRing &dst,
                 Level level = Level::authenticate)
{
    CHECK_STR(rx.set_recv(recv_spec(kToken, dst, Transport::tcp, level)).text, "");
    CHECK_STR(tx.set_send(send_spec(kToken, src, Transport::tcp, rx.data_port(), level)).text, "");
    LN_CHECK(wait_until([&] { return stats_of(tx, kToken, true).connected; }));
}

// kSamples samples of `size` bytes, at most `window` unread at a time, arrive whole, in
// order and with their timestamps.
void every_sample_in_order(unsigned spin_us, uint64_t size = 256, uint64_t kSamples = 2000,
                           uint32_t window = 256, int socket_buffer = 0)
{
    TestRing src(size, window * 2), dst(size, window * 4);
    Options o = local_options();
    o.spin_us = spin_us;
    if (socket_buffer)
        o.socket_buffer = socket_buffer;
    Forwarder rx(o), tx(o);
    connect_tcp(rx, tx, src, dst);
    Reader reader(dst);
    Publisher pub(src);
    uint64_t published = 0, received = 0;
    while (received < kSamples && !ln_test_failures) {
        // Stay well within both rings, so that nothing is lost before the network.
        while (published < kSamples && published - received < window)
            LN_CHECK_EQ(pub.publish(++published), LN_OK);
        if (reader.read(30) != LN_OK) {
            LN_CHECK(!"sample arrived");
            break;
        }
        ++received;
        LN_CHECK_EQ(reader.info.seq, received);
        LN_CHECK_EQ(reader.info.overruns, 0);
        LN_CHECK_EQ(reader.info.timestamp_ns, stamp(received));
        LN_CHECK(matches(reader.buf.data(), reader.buf.size(), received));
    }
    LN_CHECK_EQ(received, kSamples);
    LN_CHECK(wait_until([&] { return stats_of(tx, kToken, true).samples == kSamples; }));
    auto s = stats_of(tx, kToken, true);
    LN_CHECK_EQ(s.drops, 0);
    LN_CHECK_EQ(s.bytes, kSamples * size);
    LN_CHECK(s.connected);
    CHECK_STR(s.last_error, "");
    // Counted right after the write into the ring, which the reader may see first.
    LN_CHECK(wait_until([&] { return stats_of(rx, kToken, false).samples == kSamples; }));
    auto r = stats_of(rx, kToken, false);
    LN_CHECK_EQ(r.samples, kSamples);
    LN_CHECK_EQ(r.drops + r.stale + r.invalid, 0);
    LN_CHECK(r.connected);
    LN_CHECK(r.peer.rfind("127.0.0.1:", 0) == 0);
}

void test_every_sample_in_order()
{
    every_sample_in_order(0);
    every_sample_in_order(0, 64, 2000, 1); // one at a time: no frame may wait for the next
    // 1 MiB: sent from the ring slot, received whole into a ring slot.
    every_sample_in_order(0, 1 << 20, 200, 8);
}

// The same with the threads polling before they sleep (--spin-us).
void test_every_sample_in_order_polling() { every_sample_in_order(200); }

// Samples far larger than the socket buffers: the reader's direct send on an idle
// connection writes only part of a frame, and the writer must finish exactly that frame
// (from the byte where it stopped) before any other.
void test_large_samples_partly_sent()
{
    every_sample_in_order(0, 300 * 1000 + 7, 60, 4, 8192);
    every_sample_in_order(200, 300 * 1000 + 7, 60, 4, 8192);
}

// Nobody answers the hello: the queue fills up to its bound and every further sample is a
// counted drop.  The publisher is never held up (its writes just succeed).
void test_receiver_never_answers()
{
    TestRing src(1024, 128);
    StuckReceiver stuck(false);
    Options o = local_options();
    o.tcp_queue_samples = 8;
    Forwarder tx(o);
    CHECK_STR(tx.set_send(send_spec(kToken, src, Transport::tcp, stuck.port(), Level::none)).text,
              "");
    Publisher pub(src);
    for (uint64_t seq = 1; seq <= 100; ++seq)
        LN_CHECK_EQ(pub.publish(seq), LN_OK);
    LN_CHECK(wait_until([&] { return stats_of(tx, kToken, true).drops >= 92; }));
    auto s = stats_of(tx, kToken, true);
    LN_CHECK_EQ(s.drops, 92); // the newest 8 wait in the queue
    LN_CHECK_EQ(s.samples, 0);
    LN_CHECK(!s.connected);
}

// The receiver accepted the stream and then stopped reading: the socket buffers fill, the
// writer waits, the queue stays within its bound and the rest is dropped and counted.
void test_receiver_stops_reading()
{
    constexpr uint64_t kSamples = 300, kQueue = 16;
    TestRing src(64 * 1024, 512);
    StuckReceiver stuck(true);
    Options o = local_options();
    o.tcp_queue_samples = kQueue;
    o.socket_buffer = 4096;
    Forwarder tx(o);
    CHECK_STR(tx.set_send(send_spec(kToken, src, Transport::tcp, stuck.port(), Level::none)).text,
              "");
    LN_CHECK(wait_until([&] { return stats_of(tx, kToken, true).connected; }));
    Publisher pub(src);
    for (uint64_t seq = 1; seq <= kSamples; ++seq)
        LN_CHECK_EQ(pub.publish(seq), LN_OK);
    // Samples neither sent nor dropped are held by the stream: at most the queue bound.
    LN_CHECK(wait_until([&] {
        auto s = stats_of(tx, kToken, true);
        return s.samples + s.drops >= kSamples - kQueue;
    }));
    auto s = stats_of(tx, kToken, true);
    LN_CHECK(s.drops > 0);
    LN_CHECK(s.samples + s.drops <= kSamples);
    LN_CHECK(s.samples < kSamples / 2); // the stuck connection really took only a few
    LN_CHECK(s.connected);
    std::printf("    stuck receiver: %llu sent into socket buffers, %llu dropped\n",
                static_cast<unsigned long long>(s.samples),
                static_cast<unsigned long long>(s.drops));
    // tx is destroyed while its writer waits on the full socket.
}

// The receiving Forwarder goes away and a new one comes up on the same port: the sender
// notices, keeps what it could not send, reconnects and delivers everything in order.
void test_reconnect()
{
    TestRing src(128, 256), dst(128, 256);
    Options ro = local_options();
    auto rx = std::make_unique<Forwarder>(ro);
    uint16_t port = rx->data_port();
    Forwarder tx(local_options());
    CHECK_STR(rx->set_recv(recv_spec(kToken, dst, Transport::tcp)).text, "");
    CHECK_STR(tx.set_send(send_spec(kToken, src, Transport::tcp, port)).text, "");
    Reader reader(dst);
    Publisher pub(src);
    for (uint64_t seq = 1; seq <= 10; ++seq)
        LN_CHECK_EQ(pub.publish(seq), LN_OK);
    LN_CHECK(wait_until([&] { return dst.newest() == 10; }));
    LN_CHECK(stats_of(tx, kToken, true).connected);

    rx.reset();
    LN_CHECK(wait_until([&] { return !stats_of(tx, kToken, true).connected; }));
    for (uint64_t seq = 11; seq <= 20; ++seq)
        LN_CHECK_EQ(pub.publish(seq), LN_OK);
    LN_CHECK(stats_of(tx, kToken, true).last_error != "");

    ro.data_port = port;
    rx = std::make_unique<Forwarder>(ro);
    CHECK_STR(rx->set_recv(recv_spec(kToken, dst, Transport::tcp)).text, "");
    LN_CHECK(wait_until([&] { return stats_of(tx, kToken, true).connected; }));
    LN_CHECK_EQ(pub.publish(21), LN_OK);
    LN_CHECK(wait_until([&] { return dst.newest() == 21; }));
    for (uint64_t seq = 1; seq <= 21; ++seq) {
        LN_CHECK_EQ(reader.read(0), LN_OK);
        LN_CHECK_EQ(reader.info.seq, seq);
        LN_CHECK(matches(reader.buf.data(), reader.buf.size(), seq));
    }
    LN_CHECK(wait_until([&] { return stats_of(tx, kToken, true).samples == 21; }));
    LN_CHECK_EQ(stats_of(tx, kToken, true).drops, 0);
    LN_CHECK(stats_of(*rx, kToken, false).connected);
}

// A sender whose token the receiver does not know, or whose layout differs, is refused; the
// sender says why and keeps trying.
void test_refused_streams()
{
    TestRing src(128, 8), dst(128, 8), udp_dst(128, 8);
    Forwarder rx(local_options()), tx(local_options());
    CHECK_STR(tx.set_send(send_spec(kToken, src, Transport::tcp, rx.data_port())).text, "");
    LN_CHECK(wait_until([&] { return rx.totals().unknown_stream >= 1; }));
    LN_CHECK(wait_until([&] {
        return stats_of(tx, kToken, true).last_error.find("no TCP stream") != std::string::npos;
    }));
    CHECK_STR(rx.set_recv(recv_spec(kToken, udp_dst, Transport::udp)).text, ""); // wrong transport
    uint64_t unknown = rx.totals().unknown_stream;
    LN_CHECK(wait_until([&] { return rx.totals().unknown_stream > unknown; }));
    LN_CHECK(!stats_of(tx, kToken, true).connected);

    auto spec = recv_spec(kToken, dst, Transport::tcp);
    CHECK_STR(rx.set_recv(spec).text, "");
    LN_CHECK(wait_until([&] { return stats_of(tx, kToken, true).connected; }));
    // The receiver's ring has another layout than the sender's: refused, counted there.
    TestRing other(128, 8, kHash + 1);
    CHECK_STR(rx.set_recv(recv_spec(kToken, other, Transport::tcp)).text, "");
    LN_CHECK(wait_until([&] { return stats_of(rx, kToken, false).invalid >= 1; }));
    LN_CHECK(wait_until(
        [&] { return stats_of(tx, kToken, true).last_error.find("layout") != std::string::npos; }));
    LN_CHECK(!stats_of(tx, kToken, true).connected);
    LN_CHECK_EQ(other.newest(), 0);
}

// Hellos and frames that are wrong end their connection and are counted; nothing of them
// reaches the ring.
void test_bad_hello_and_frames()
{
    TestRing dst(128, 8);
    Forwarder rx(local_options());
    CHECK_STR(rx.set_recv(recv_spec(kToken, dst, Transport::tcp, Level::none)).text, "");
    {
        Client c(rx.data_port());
        uint8_t junk[wire::kHelloSize];
        std::memset(junk, 0x5a, sizeof junk);
        c.send(junk, sizeof junk);
        LN_CHECK(c.closed_by_peer());
        LN_CHECK_EQ(rx.totals().malformed, 1);
    }
    {
        Client c(rx.data_port());
        uint8_t hello[wire::kHelloSize];
        wire::encode_hello(hello, {kToken, 128, kHash});
        c.send(hello, sizeof hello);
        LN_CHECK(c.reply().kind == wire::Kind::accept);
        LN_CHECK(wait_until([&] { return stats_of(rx, kToken, false).connected; }));
        // The receiver wakes once a whole frame's bytes are there; the size is refused
        // before any payload is read into the ring.
        uint8_t frame[wire::kFrameHeaderSize + 129 + wire::kFrameTrailerSize] = {};
        wire::encode_frame_header(frame, {1, stamp(1), 129});
        c.send(frame, sizeof frame);
        LN_CHECK(c.closed_by_peer());
        LN_CHECK(wait_until([&] { return !stats_of(rx, kToken, false).connected; }));
    }
    auto r = stats_of(rx, kToken, false);
    LN_CHECK_EQ(r.invalid, 1);
    LN_CHECK_EQ(r.samples, 0);
    LN_CHECK(r.last_error.find("129") != std::string::npos);
    LN_CHECK_EQ(dst.newest(), 0);
    {
        Client c(rx.data_port()); // a good frame still goes in
        uint8_t hello[wire::kHelloSize];
        wire::encode_hello(hello, {kToken, 128, kHash});
        c.send(hello, sizeof hello);
        LN_CHECK(c.reply().kind == wire::Kind::accept);
        uint8_t frame[wire::kFrameHeaderSize + 128 + wire::kFrameTrailerSize];
        wire::encode_frame_header(frame, {3, stamp(3), 128});
        fill(frame + wire::kFrameHeaderSize, 128, 3);
        wire::encode_frame_trailer(frame + wire::kFrameHeaderSize + 128, true);
        c.send(frame, sizeof frame);
        LN_CHECK(wait_until([&] { return stats_of(rx, kToken, false).samples == 1; }));
    }
    LN_CHECK_EQ(dst.newest(), 3);
}

// A frame of level none: header, `size` bytes of fill(seq), the trailer.
std::vector<uint8_t> plain_frame(uint64_t seq, size_t size, bool intact)
{
    std::vector<uint8_t> f(wire::kFrameHeaderSize + size + wire::kFrameTrailerSize);
    wire::encode_frame_header(f.data(), {seq, stamp(seq), size});
    fill(f.data() + wire::kFrameHeaderSize, size, seq);
    wire::encode_frame_trailer(f.data() + wire::kFrameHeaderSize + size, intact);
    return f;
}

// The hello of stream kToken with messages of `size` bytes, and the receiver's accept.
void say_hello(Client &c, size_t size)
{
    uint8_t hello[wire::kHelloSize];
    wire::encode_hello(hello, {kToken, size, kHash});
    c.send(hello, sizeof hello);
    LN_CHECK(c.reply().kind == wire::Kind::accept);
}

// A frame whose trailer says it was torn while sent is dropped (counted) and the next one
// goes in, whole or fed in pieces; a frame with no trailer where it belongs costs the
// connection and nothing reaches the ring.
void test_frame_trailers()
{
    constexpr size_t kSize = 4096;
    TestRing dst(kSize, 8);
    Forwarder rx(local_options());
    CHECK_STR(rx.set_recv(recv_spec(kToken, dst, Transport::tcp, Level::none)).text, "");
    auto frame = [](uint64_t seq, bool intact) { return plain_frame(seq, kSize, intact); };
    Reader reader(dst);
    {
        Client c(rx.data_port());
        say_hello(c, kSize);
        auto torn = frame(1, false);
        c.send(torn.data(), torn.size());
        auto good = frame(2, true);
        for (size_t at = 0; at < good.size(); at += 1000) { // in pieces, with pauses
            c.send(good.data() + at, std::min<size_t>(1000, good.size() - at));
            std::this_thread::sleep_for(std::chrono::milliseconds(2));
        }
        LN_CHECK(wait_until([&] { return stats_of(rx, kToken, false).samples == 1; }));
        LN_CHECK_EQ(reader.read(5), LN_OK);
        LN_CHECK_EQ(reader.info.seq, 2);
        LN_CHECK(matches(reader.buf.data(), kSize, 2));
        LN_CHECK_EQ(stats_of(rx, kToken, false).drops, 1);
        auto bad = frame(3, true);
        bad[bad.size() - 8] = 'X'; // the trailer's place holds something else
        c.send(bad.data(), bad.size());
        LN_CHECK(c.closed_by_peer());
    }
    auto r = stats_of(rx, kToken, false);
    LN_CHECK_EQ(r.samples, 1);
    LN_CHECK_EQ(r.invalid, 1);
    LN_CHECK(r.last_error.find("trailer") != std::string::npos);
    LN_CHECK_EQ(dst.newest(), 2);
    LN_CHECK(reader.read(0) != LN_OK);
}

// Large frames are received into a ring slot as they arrive; one that stalls (here for
// 20 ms, ten times the receiver's patience with the ring's lock held) in its payload,
// between payload and trailer or inside the trailer goes on through the private buffer:
// every one arrives whole and in order, the one sent in a single piece too.
void test_large_frames_that_stall()
{
    constexpr size_t kSize = 256 * 1024,
                     kFrame = wire::kFrameHeaderSize + kSize + wire::kFrameTrailerSize;
    TestRing dst(kSize, 8);
    Forwarder rx(local_options());
    CHECK_STR(rx.set_recv(recv_spec(kToken, dst, Transport::tcp, Level::none)).text, "");
    Reader reader(dst);
    Client c(rx.data_port());
    say_hello(c, kSize);
    // Where each frame pauses: none, mid-payload, after the payload, inside the trailer.
    const size_t pauses[] = {0, wire::kFrameHeaderSize + kSize / 3, wire::kFrameHeaderSize + kSize,
                             kFrame - 3};
    uint64_t seq = 0;
    for (size_t pause : pauses) {
        ++seq;
        std::vector<uint8_t> f = plain_frame(seq, kSize, true);
        if (pause == 0) {
            c.send(f.data(), f.size());
        } else {
            c.send(f.data(), pause);
            std::this_thread::sleep_for(std::chrono::milliseconds(20));
            c.send(f.data() + pause, f.size() - pause);
        }
        LN_CHECK_EQ(reader.read(5), LN_OK);
        LN_CHECK_EQ(reader.info.seq, seq);
        LN_CHECK_EQ(reader.info.timestamp_ns, stamp(seq));
        LN_CHECK(matches(reader.buf.data(), kSize, seq));
    }
    // The counter follows the commit that woke the reader.
    LN_CHECK(wait_until([&] { return stats_of(rx, kToken, false).samples == seq; }));
    auto r = stats_of(rx, kToken, false);
    LN_CHECK_EQ(r.drops + r.invalid + r.stale, 0);
}

// The publisher floods a ring of two slots far faster than the stream sends: the sender,
// sending straight from the slots (level none; authenticate, which tags the slot while it
// is borrowed; encrypt, which enciphers from it), has samples overwritten under it.  Every
// sample that arrives is intact and in order; the rest is counted as dropped on the sending
// side; a torn frame's tag is authentic (covering header and trailer), so nothing is
// rejected.
void overwritten_while_sent(Level level)
{
    constexpr uint64_t kSize = 64 * 1024, kPublished = 400;
    TestRing src(kSize, 2), dst(kSize, 512);
    Options o = local_options();
    o.socket_buffer = 16 * 1024; // the socket takes little at once: sending takes a while
    Forwarder rx(o), tx(o);
    connect_tcp(rx, tx, src, dst, level);
    Reader reader(dst);
    Publisher pub(src);
    for (uint64_t seq = 1; seq <= kPublished; ++seq)
        LN_CHECK_EQ(pub.publish(seq), LN_OK);
    LN_CHECK(wait_until([&] {
        auto s = stats_of(tx, kToken, true);
        return s.samples + s.drops == kPublished;
    }));
    auto s = stats_of(tx, kToken, true);
    LN_CHECK(s.samples > 0);
    LN_CHECK(wait_until([&] { return stats_of(rx, kToken, false).samples == s.samples; }));
    uint64_t last = 0, got = 0;
    while (reader.read(0.5) == LN_OK) {
        if (reader.info.seq <= last)
            std::printf("    seq %llu after %llu\n", (unsigned long long)reader.info.seq,
                        (unsigned long long)last);
        LN_CHECK(reader.info.seq > last);
        LN_CHECK(matches(reader.buf.data(), kSize, reader.info.seq));
        last = reader.info.seq;
        ++got;
    }
    LN_CHECK(got > 0);
    auto r = stats_of(rx, kToken, false);
    LN_CHECK_EQ(r.invalid + r.stale + r.rejected, 0);
    LN_CHECK_EQ(r.samples, s.samples);
    LN_CHECK_EQ(got, s.samples); // the destination ring holds them all
    std::printf("    flood through 2 slots: %llu sent, %llu dropped (%llu of them torn)\n",
                static_cast<unsigned long long>(s.samples),
                static_cast<unsigned long long>(s.drops), static_cast<unsigned long long>(r.drops));
}

void test_overwritten_while_sent() { overwritten_while_sent(Level::none); }
void test_overwritten_while_sent_with_a_key() { overwritten_while_sent(Level::authenticate); }
void test_overwritten_while_sent_encrypted() { overwritten_while_sent(Level::encrypt); }

} // namespace

int main()
{
    LN_TEST_RUN(test_every_sample_in_order);
    LN_TEST_RUN(test_every_sample_in_order_polling);
    LN_TEST_RUN(test_large_samples_partly_sent);
    LN_TEST_RUN(test_receiver_never_answers);
    LN_TEST_RUN(test_receiver_stops_reading);
    LN_TEST_RUN(test_reconnect);
    LN_TEST_RUN(test_refused_streams);
    LN_TEST_RUN(test_bad_hello_and_frames);
    LN_TEST_RUN(test_frame_trailers);
    LN_TEST_RUN(test_large_frames_that_stall);
    LN_TEST_RUN(test_overwritten_while_sent);
    LN_TEST_RUN(test_overwritten_while_sent_with_a_key);
    LN_TEST_RUN(test_overwritten_while_sent_encrypted);
    LN_TEST_EXIT();
}
