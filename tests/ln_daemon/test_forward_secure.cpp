// test_forward_secure.cpp — authenticated and encrypted forwarding through real Forwarders:
// forged, replayed, truncated, reordered and foreign-key datagrams and frames are dropped and
// counted as rejected while the stream and other streams keep delivering; encrypted samples
// arrive intact and their bytes never cross the wire in the clear; a key change restarts the
// streams.
#include <algorithm>
#include <atomic>
#include <cstring>
#include <mutex>
#include <poll.h>
#include <sodium.h>
#include <thread>
#include <vector>

#include "forward_test.hpp"
#include "forward_crypto.hpp"
#include "forward_tcp_frame.hpp"
#include "forward_wire.hpp"

using namespace fwdtest;
using lnd::Key;
using lnd::fwd::Forwarder;
using lnd::fwd::Level;
using lnd::fwd::Options;
using lnd::fwd::Transport;
namespace wire = lnd::fwd::wire;
namespace sec = lnd::fwd::sec;

namespace {

Key key_of(uint8_t byte)
{
    Key k;
    std::memset(k.bytes, byte, Key::kBytes);
    return k;
}

// The sequence numbers of every sample the reader can still get, each checked whole.
std::vector<uint64_t> drain_seqs(Reader &reader)
{
    std::vector<uint64_t> seqs;
    while (reader.read(0) == LN_OK) {
        seqs.push_back(reader.info.seq);
        LN_CHECK(matches(reader.buf.data(), reader.buf.size(), reader.info.seq));
    }
    return seqs;
}

Options keyed(const Key &k)
{
    Options o = local_options();
    o.key = k;
    return o;
}

// Builds the datagrams a sender with daemon key `daemon` would send for `token`.
class Crafter {
public:
    Crafter(const Key &daemon, uint64_t token, uint64_t salt) : token_(token), salt_(salt)
    {
        Key stream, k;
        sec::stream_key(daemon, token, 0, stream);
        uint8_t raw[8];
        for (int i = 0; i < 8; ++i)
            raw[i] = static_cast<uint8_t>(salt >> (8 * i));
        sec::sub_key(stream, "udp salt", raw, sizeof raw, k);
        box_ = std::make_unique<sec::Box>(k, sec::Suite::poly1305);
    }
    // Fragment `index` of sample `seq` (3000 bytes, chunks of 1000) under `counter`.
    std::vector<uint8_t> datagram(uint64_t seq, uint32_t index, uint64_t counter)
    {
        constexpr uint64_t kSize = 3000;
        constexpr uint16_t kChunk = 1000;
        std::vector<uint8_t> sample(kSize);
        fill(sample.data(), kSize, seq);
        wire::Fragment f;
        f.token = token_;
        f.seq = seq;
        f.timestamp_ns = stamp(seq);
        f.sample_size = kSize;
        f.chunk_size = kChunk;
        f.count = 3;
        f.index = index;
        f.suite = static_cast<uint8_t>(sec::Suite::poly1305);
        f.salt = salt_;
        f.counter = counter;
        std::vector<uint8_t> d(wire::kFragmentHeaderSize + kChunk + sec::kTagBytes);
        wire::encode_fragment_header(d.data(), f);
        uint8_t *payload = d.data() + wire::kFragmentHeaderSize;
        std::memcpy(payload, sample.data() + index * kChunk, kChunk);
        box_->seal(counter, d.data(), wire::kFragmentHeaderSize, payload, kChunk, nullptr,
                   payload + kChunk);
        return d;
    }
    // All fragments of `seq`, counters from `first` on.
    std::vector<std::vector<uint8_t>> sample(uint64_t seq, uint64_t first)
    {
        return {datagram(seq, 0, first), datagram(seq, 1, first + 1), datagram(seq, 2, first + 2)};
    }

private:
    uint64_t token_, salt_;
    std::unique_ptr<sec::Box> box_;
};

// A UDP relay that keeps a copy of every byte it passes on.
class Tap {
public:
    explicit Tap(uint16_t target) : target_(target), thread_([this] { run(); }) {}
    ~Tap()
    {
        stop_ = true;
        thread_.join();
    }
    uint16_t port() const { return local_port(in_.fd()); }
    bool saw(const std::vector<uint8_t> &needle)
    {
        std::lock_guard<std::mutex> lock(mutex_);
        return std::search(bytes_.begin(), bytes_.end(), needle.begin(), needle.end()) !=
               bytes_.end();
    }
    size_t size()
    {
        std::lock_guard<std::mutex> lock(mutex_);
        return bytes_.size();
    }

private:
    void run()
    {
        std::vector<uint8_t> buf(65536);
        while (!stop_) {
            pollfd p = {in_.fd(), POLLIN, 0};
            if (::poll(&p, 1, 20) <= 0)
                continue;
            ssize_t n = ::recv(in_.fd(), buf.data(), buf.size(), 0);
            if (n <= 0)
                continue;
            {
                std::lock_guard<std::mutex> lock(mutex_);
                bytes_.insert(bytes_.end(), buf.begin(), buf.begin() + n);
            }
            out_.send_to(target_, buf.data(), static_cast<size_t>(n));
        }
    }

    UdpSocket in_, out_;
    uint16_t target_;
    std::mutex mutex_;
    std::vector<uint8_t> bytes_;
    std::atomic<bool> stop_{false};
    std::thread thread_;
};

void test_udp_attacks()
{
    const Key k = key_of(0x11);
    TestRing ring(3000, 16), other_src(64, 16), other_dst(64, 16);
    Forwarder rx(keyed(k)), tx(keyed(k));
    CHECK_STR(rx.set_recv(recv_spec(1, ring, Transport::udp)).text, "");
    // Another topic from a real sender, on the same receiver: it must not notice anything.
    CHECK_STR(rx.set_recv(recv_spec(2, other_dst, Transport::udp)).text, "");
    CHECK_STR(tx.set_send(send_spec(2, other_src, Transport::udp, rx.data_port())).text, "");
    Publisher other(other_src);
    Reader reader(ring), other_reader(other_dst);
    UdpSocket sock;
    auto send = [&](const std::vector<uint8_t> &d) {
        sock.send_to(rx.data_port(), d.data(), d.size());
    };
    auto rejected = [&] { return stats_of(rx, 1, false).rejected; };
    const uint64_t salt = uint64_t{5} << 40;
    Crafter good(k, 1, salt);

    for (auto &d : good.sample(5, 1))
        send(d);
    LN_CHECK(wait_until([&] { return stats_of(rx, 1, false).samples == 1; }));
    LN_CHECK_EQ(other.publish(1), LN_OK);

    auto forged = good.datagram(6, 0, 4);
    forged[wire::kFragmentHeaderSize + 10] ^= 1; // a payload byte
    send(forged);
    LN_CHECK(wait_until([&] { return rejected() == 1; }));
    send(good.datagram(5, 0, 1)); // replayed
    LN_CHECK(wait_until([&] { return rejected() == 2; }));
    auto cut = good.datagram(6, 0, 5);
    cut.pop_back(); // truncated
    send(cut);
    LN_CHECK(wait_until([&] { return rejected() == 3; }));
    Crafter foreign(key_of(0x22), 1, salt); // another key
    send(foreign.datagram(6, 0, 6));
    LN_CHECK(wait_until([&] { return rejected() == 4; }));
    auto mislabelled = good.datagram(6, 0, 7);
    mislabelled[63] = 0; // claims suite none: not this stream's level
    send(mislabelled);
    LN_CHECK(wait_until([&] { return rejected() == 5; }));
    LN_CHECK_EQ(other.publish(2), LN_OK);

    // Reordered: within the window a late datagram still counts, beyond it it is rejected.
    const uint64_t far = 100 + sec::ReplayWindow::kBits;
    auto s7 = good.sample(7, far);
    send(s7[2]);
    send(s7[0]);
    send(s7[1]);
    LN_CHECK(wait_until([&] { return stats_of(rx, 1, false).samples == 2; }));
    send(good.datagram(8, 0, far + 2 - sec::ReplayWindow::kBits)); // too old
    LN_CHECK(wait_until([&] { return rejected() == 6; }));

    // A sender that restarted (newer salt) is taken; a recording of the older salt is not.
    Crafter restarted(k, 1, salt + 1);
    for (auto &d : restarted.sample(9, 1))
        send(d);
    LN_CHECK(wait_until([&] { return stats_of(rx, 1, false).samples == 3; }));
    send(good.datagram(10, 0, far + 10));
    LN_CHECK(wait_until([&] { return rejected() == 7; }));

    LN_CHECK(drain_seqs(reader) == (std::vector<uint64_t>{5, 7, 9}));
    auto r = stats_of(rx, 1, false);
    LN_CHECK_EQ(r.invalid + r.stale, 0);
    LN_CHECK(r.last_error.find("rejected") != std::string::npos);
    // The other stream delivers still, and saw nothing of it.
    uint64_t other_seq = 2;
    LN_CHECK(wait_until([&] {
        other.publish(++other_seq);
        return stats_of(rx, 2, false).samples >= 3;
    }));
    LN_CHECK_EQ(stats_of(rx, 2, false).rejected, 0);
    LN_CHECK_EQ(rx.totals().malformed, 0);
}

// The sender has another key or level: everything it sends is rejected, nothing delivered;
// once it has the receiver's key (a key change) the stream delivers.
void test_udp_foreign_key_then_rotation()
{
    TestRing src(64, 16), dst(64, 16), plain_src(64, 16), plain_dst(64, 16);
    Forwarder rx(keyed(key_of(1))), tx(keyed(key_of(2)));
    CHECK_STR(rx.set_recv(recv_spec(3, dst, Transport::udp)).text, "");
    CHECK_STR(tx.set_send(send_spec(3, src, Transport::udp, rx.data_port())).text, "");
    // A stream of level none sent to a receiver of level authenticate.
    CHECK_STR(rx.set_recv(recv_spec(4, plain_dst, Transport::udp)).text, "");
    CHECK_STR(
        tx.set_send(send_spec(4, plain_src, Transport::udp, rx.data_port(), Level::none)).text, "");
    Publisher pub(src), plain(plain_src);
    uint64_t seq = 0;
    LN_CHECK(wait_until([&] {
        pub.publish(++seq);
        plain.publish(seq);
        return stats_of(rx, 3, false).rejected >= 3 && stats_of(rx, 4, false).rejected >= 3;
    }));
    LN_CHECK_EQ(stats_of(rx, 3, false).samples, 0);
    LN_CHECK_EQ(stats_of(rx, 4, false).samples, 0);
    LN_CHECK_EQ(dst.newest(), 0);
    CHECK_STR(tx.set_key(key_of(1)).text, "");
    LN_CHECK(wait_until([&] {
        pub.publish(++seq);
        return stats_of(rx, 3, false).samples >= 3;
    }));
}

// `encrypt`: the samples arrive intact, and no sample's bytes are seen on the wire.
void encrypted(Transport t)
{
    const Key k = key_of(0x33);
    TestRing src(5000, 16), dst(5000, 16);
    Forwarder rx(keyed(k)), tx(keyed(k));
    CHECK_STR(rx.set_recv(recv_spec(5, dst, t, Level::encrypt)).text, "");
    Tap tap(rx.data_port());
    if (t == Transport::udp) {
        CHECK_STR(tx.set_send(send_spec(5, src, t, tap.port(), Level::encrypt)).text, "");
    } else {
        CHECK_STR(tx.set_send(send_spec(5, src, t, rx.data_port(), Level::encrypt)).text, "");
    }
    Publisher pub(src);
    Reader reader(dst);
    for (uint64_t seq = 1; seq <= 3; ++seq) {
        LN_CHECK_EQ(pub.publish(seq), LN_OK);
        LN_CHECK_EQ(reader.read(10), LN_OK);
        LN_CHECK_EQ(reader.info.seq, seq);
        LN_CHECK_EQ(reader.info.timestamp_ns, stamp(seq));
        LN_CHECK(matches(reader.buf.data(), reader.buf.size(), seq));
    }
    if (t == Transport::udp) {
        LN_CHECK(tap.size() > 3 * 5000);
        std::vector<uint8_t> clear(5000);
        fill(clear.data(), clear.size(), 2);
        LN_CHECK(!tap.saw(std::vector<uint8_t>(clear.begin() + 1000, clear.begin() + 1032)));
    }
    LN_CHECK_EQ(stats_of(rx, 5, false).rejected, 0);
}

void test_encrypt_udp() { encrypted(Transport::udp); }
void test_encrypt_tcp() { encrypted(Transport::tcp); }

// TCP: a sender with another key is refused at its hello; a connection that passed the
// handshake and then sends a forged frame is closed; a new one delivers again.
void test_tcp_attacks()
{
    const Key k = key_of(0x44);
    constexpr uint64_t kToken = 6, kSize = 128;
    TestRing src(kSize, 16), dst(kSize, 16);
    Forwarder rx(keyed(k));
    CHECK_STR(rx.set_recv(recv_spec(kToken, dst, Transport::tcp)).text, "");
    {
        Forwarder tx(keyed(key_of(0x45)));
        CHECK_STR(tx.set_send(send_spec(kToken, src, Transport::tcp, rx.data_port())).text, "");
        LN_CHECK(wait_until([&] { return stats_of(rx, kToken, false).rejected >= 1; }));
        LN_CHECK(wait_until([&] {
            return stats_of(tx, kToken, true).last_error.find("key") != std::string::npos;
        }));
        LN_CHECK(!stats_of(tx, kToken, true).connected);
    }
    const uint64_t before = stats_of(rx, kToken, false).rejected;

    // A hand-made sender that knows the key, so it gets through the handshake.
    auto connect = [&](std::unique_ptr<sec::Box> &box) {
        auto fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
        sockaddr_in a = loopback(rx.data_port());
        LN_CHECK_EQ(::connect(fd, reinterpret_cast<sockaddr *>(&a), sizeof a), 0);
        lnd::fwd::SendSpec spec = send_spec(kToken, src, Transport::tcp, rx.data_port());
        Key stream;
        sec::stream_key(k, kToken, 1, stream);
        uint8_t nonce[wire::kHandshakeNonce];
        randombytes_buf(nonce, sizeof nonce);
        uint8_t hello[wire::kHelloSize], raw[wire::kReplySize];
        lnd::fwd::encode_tcp_hello(spec, stream, sec::Suite::poly1305, nonce, hello);
        LN_CHECK_EQ(::send(fd, hello, sizeof hello, 0), static_cast<ssize_t>(sizeof hello));
        LN_CHECK_EQ(::recv(fd, raw, sizeof raw, MSG_WAITALL), static_cast<ssize_t>(sizeof raw));
        wire::Reply reply;
        LN_CHECK(wire::decode_reply(raw, reply));
        LN_CHECK(lnd::fwd::check_tcp_reply(hello, reply, raw, stream, sec::Suite::poly1305, box));
        return fd;
    };
    auto frame = [&](sec::Box &box, uint64_t counter, uint64_t seq) {
        std::vector<uint8_t> f(wire::kFrameHeaderSize + kSize + wire::kFrameTrailerSize +
                               sec::kTagBytes);
        wire::encode_frame_header(f.data(), {seq, stamp(seq), kSize});
        fill(f.data() + wire::kFrameHeaderSize, kSize, seq);
        uint8_t *trailer = f.data() + wire::kFrameHeaderSize + kSize;
        wire::encode_frame_trailer(trailer, true);
        box.seal(counter, f.data(), wire::kFrameHeaderSize, f.data() + wire::kFrameHeaderSize,
                 kSize, nullptr, trailer + wire::kFrameTrailerSize, trailer,
                 wire::kFrameTrailerSize);
        return f;
    };
    {
        std::unique_ptr<sec::Box> box;
        int fd = connect(box);
        auto good = frame(*box, 1, 1);
        ::send(fd, good.data(), good.size(), MSG_NOSIGNAL);
        LN_CHECK(wait_until([&] { return stats_of(rx, kToken, false).samples == 1; }));
        auto forged = frame(*box, 2, 2);
        forged[wire::kFrameHeaderSize + 3] ^= 4;
        ::send(fd, forged.data(), forged.size(), MSG_NOSIGNAL);
        char byte;
        LN_CHECK(::recv(fd, &byte, 1, 0) <= 0); // closed by the receiver
        ::close(fd);
    }
    LN_CHECK(wait_until([&] { return stats_of(rx, kToken, false).rejected == before + 1; }));
    {
        std::unique_ptr<sec::Box> box;
        int fd = connect(box);
        auto good = frame(*box, 1, 3);
        ::send(fd, good.data(), good.size(), MSG_NOSIGNAL);
        LN_CHECK(wait_until([&] { return stats_of(rx, kToken, false).samples == 2; }));
        ::close(fd);
    }
    LN_CHECK_EQ(dst.newest(), 3);
    LN_CHECK_EQ(stats_of(rx, kToken, false).invalid, 0);
}

} // namespace

int main()
{
    LN_CHECK(sodium_init() >= 0);
    LN_TEST_RUN(test_udp_attacks);
    LN_TEST_RUN(test_udp_foreign_key_then_rotation);
    LN_TEST_RUN(test_encrypt_udp);
    LN_TEST_RUN(test_encrypt_tcp);
    LN_TEST_RUN(test_tcp_attacks);
    LN_TEST_EXIT();
}
