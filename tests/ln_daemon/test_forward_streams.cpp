// Tests of the Forwarder's stream table and lifetime: specs that cannot work are refused
// with a reason, set_send/set_recv with a known token replace the stream, remove stops it
// for good, stats() may run alongside, and destroying Forwarders while samples flow in
// every direction is clean (the sanitizer build runs this too).
#include <atomic>
#include <cstdio>
#include <memory>
#include <system_error>
#include <thread>
#include <vector>

#include "forward_test.hpp"
#include "forward_wire.hpp"

using namespace fwdtest;
using lnd::fwd::Forwarder;
using lnd::fwd::Options;
using lnd::fwd::Transport;
namespace wire = lnd::fwd::wire;

namespace {

constexpr uint64_t kToken = 0x99990000aaaa0001ull;

bool contains(const std::string &text, const std::string &part)
{
    bool found = text.find(part) != std::string::npos;
    if (!found)
        std::fprintf(stderr, "    \"%s\" does not contain \"%s\"\n", text.c_str(), part.c_str());
    return found;
}

void test_refused_specs()
{
    TestRing ring(64, 4);
    Options o = local_options();
    o.tcp_queue_bytes = 1000;
    Forwarder f(o);
    auto send = send_spec(kToken, ring, Transport::udp, 9);
    auto bad = send;
    bad.token = 0;
    LN_CHECK(contains(f.set_send(bad).text, "token 0"));
    bad = send;
    bad.ring = "/ln.fwdtest-no-such-ring";
    LN_CHECK(contains(f.set_send(bad).text, "no-such-ring"));
    bad = send;
    bad.layout_hash = kHash + 1;
    LN_CHECK(contains(f.set_send(bad).text, "hash"));
    bad = send;
    bad.message_size = 65;
    LN_CHECK(!f.set_send(bad).text.empty());
    bad = send;
    bad.host = "";
    LN_CHECK(contains(f.set_send(bad).text, "host"));
    bad = send;
    bad.port = 0;
    LN_CHECK(contains(f.set_send(bad).text, "port"));
    TestRing big(4096, 4);
    LN_CHECK(contains(f.set_send(send_spec(kToken, big, Transport::tcp, 9)).text, "TCP queue"));
    auto recv = recv_spec(kToken, ring, Transport::udp);
    recv.ring = "/ln.fwdtest-no-such-ring";
    LN_CHECK(contains(f.set_recv(recv).text, "no-such-ring"));
    LN_CHECK(f.stats().empty());
    LN_CHECK(!f.remove(kToken));

    // Options that cannot work, and a data port that is taken, are refused at construction.
    Options huge = local_options();
    huge.udp_payload = wire::kMaxChunk + 1;
    bool threw = false;
    try {
        Forwarder g(huge);
    } catch (const std::system_error &e) {
        threw = contains(e.what(), "udp_payload");
    }
    LN_CHECK(threw);
    Options taken = local_options();
    taken.data_port = f.data_port();
    threw = false;
    try {
        Forwarder g(taken);
    } catch (const std::system_error &e) {
        threw = contains(e.what(), std::to_string(f.data_port()));
    }
    LN_CHECK(threw);
}

// set_send with a known token moves the stream: once it returned, nothing more goes to the
// old destination.  set_recv with a known token moves the writing to the new ring.
void test_replace()
{
    TestRing src(64, 8), dst1(64, 8), dst2(64, 8), dst3(64, 8);
    Forwarder rx1(local_options()), rx2(local_options()), tx(local_options());
    CHECK_STR(rx1.set_recv(recv_spec(kToken, dst1, Transport::udp)).text, "");
    CHECK_STR(rx2.set_recv(recv_spec(kToken, dst2, Transport::udp)).text, "");
    CHECK_STR(tx.set_send(send_spec(kToken, src, Transport::udp, rx1.data_port())).text, "");
    Publisher pub(src);
    LN_CHECK_EQ(pub.publish(1), LN_OK);
    LN_CHECK(wait_until([&] { return dst1.newest() == 1; }));

    CHECK_STR(tx.set_send(send_spec(kToken, src, Transport::udp, rx2.data_port())).text, "");
    LN_CHECK_EQ(pub.publish(2), LN_OK);
    LN_CHECK(wait_until([&] { return dst2.newest() == 2; }));
    LN_CHECK_EQ(dst1.newest(), 1);
    auto all = tx.stats();
    LN_CHECK_EQ(all.size(), 1);
    CHECK_STR(all.at(0).peer, "127.0.0.1:" + std::to_string(rx2.data_port()));

    CHECK_STR(rx2.set_recv(recv_spec(kToken, dst3, Transport::udp)).text, "");
    LN_CHECK_EQ(pub.publish(3), LN_OK);
    LN_CHECK(wait_until([&] { return dst3.newest() == 3; }));
    LN_CHECK_EQ(dst2.newest(), 2);
    LN_CHECK_EQ(rx2.stats().size(), 1);
    CHECK_STR(rx2.stats().at(0).ring, dst3.name());

    // Replacing UDP by TCP (and back) on both ends.
    CHECK_STR(rx2.set_recv(recv_spec(kToken, dst3, Transport::tcp)).text, "");
    CHECK_STR(tx.set_send(send_spec(kToken, src, Transport::tcp, rx2.data_port())).text, "");
    LN_CHECK(wait_until([&] { return stats_of(tx, kToken, true).connected; }));
    LN_CHECK_EQ(pub.publish(4), LN_OK);
    LN_CHECK(wait_until([&] { return dst3.newest() == 4; }));
    CHECK_STR(rx2.set_recv(recv_spec(kToken, dst3, Transport::udp)).text, "");
    CHECK_STR(tx.set_send(send_spec(kToken, src, Transport::udp, rx2.data_port())).text, "");
    LN_CHECK_EQ(pub.publish(5), LN_OK);
    LN_CHECK(wait_until([&] { return dst3.newest() == 5; }));
}

// remove() stops a stream for good: the sender is gone from the stats, datagrams for a
// removed receiving stream count as unknown, and a second remove finds nothing.
void test_remove()
{
    TestRing src(64, 8), dst(64, 8), tsrc(64, 8), tdst(64, 8);
    Forwarder rx(local_options()), tx(local_options());
    CHECK_STR(rx.set_recv(recv_spec(kToken, dst, Transport::udp)).text, "");
    CHECK_STR(rx.set_recv(recv_spec(kToken + 1, tdst, Transport::tcp)).text, "");
    CHECK_STR(tx.set_send(send_spec(kToken, src, Transport::udp, rx.data_port())).text, "");
    CHECK_STR(tx.set_send(send_spec(kToken + 1, tsrc, Transport::tcp, rx.data_port())).text, "");
    LN_CHECK(wait_until([&] { return stats_of(rx, kToken + 1, false).connected; }));
    LN_CHECK_EQ(tx.stats().size(), 2);

    LN_CHECK(tx.remove(kToken));
    LN_CHECK(!tx.remove(kToken));
    LN_CHECK_EQ(tx.stats().size(), 1);
    LN_CHECK(rx.remove(kToken));
    LN_CHECK_EQ(rx.stats().size(), 1);
    UdpSocket sock;
    wire::Fragment f;
    f.token = kToken;
    f.seq = 1;
    f.sample_size = 64;
    f.chunk_size = 1400;
    f.count = 1;
    std::vector<uint8_t> d(wire::kFragmentHeaderSize + 64);
    wire::encode_fragment_header(d.data(), f);
    sock.send_to(rx.data_port(), d.data(), d.size());
    LN_CHECK(wait_until([&] { return rx.totals().unknown_stream == 1; }));
    LN_CHECK_EQ(dst.newest(), 0);

    // Removing the receiving TCP stream closes its connection; the sender notices.
    LN_CHECK(rx.remove(kToken + 1));
    LN_CHECK(wait_until([&] { return !stats_of(tx, kToken + 1, true).connected; }));
    LN_CHECK(rx.stats().empty());
    LN_CHECK(tx.remove(kToken + 1));
    LN_CHECK(tx.stats().empty());
}

// Forwarders destroyed while publishers write and every kind of stream carries samples,
// in both directions, while another thread reads stats().
void test_destroy_while_running()
{
    struct Pair {
        uint64_t size;
        Transport transport;
        std::unique_ptr<TestRing> src, dst;
    };
    std::vector<Pair> pairs;
    for (uint64_t size : {64u, 1u << 20})
        for (Transport t : {Transport::udp, Transport::tcp})
            for (int direction = 0; direction < 2; ++direction)
                pairs.push_back({size, t, std::make_unique<TestRing>(size, 4),
                                 std::make_unique<TestRing>(size, 4)});
    auto a = std::make_unique<Forwarder>(local_options());
    auto b = std::make_unique<Forwarder>(local_options());
    for (size_t i = 0; i < pairs.size(); ++i) {
        Forwarder &from = i % 2 ? *a : *b, &to = i % 2 ? *b : *a;
        uint64_t token = kToken + 100 + i;
        CHECK_STR(to.set_recv(recv_spec(token, *pairs[i].dst, pairs[i].transport)).text, "");
        CHECK_STR(
            from.set_send(send_spec(token, *pairs[i].src, pairs[i].transport, to.data_port())).text,
            "");
    }
    std::atomic<bool> stop{false};
    std::thread publisher([&] {
        std::vector<std::unique_ptr<Publisher>> pubs;
        for (auto &p : pairs)
            pubs.push_back(std::make_unique<Publisher>(*p.src));
        for (uint64_t seq = 1; !stop; ++seq) {
            for (auto &pub : pubs)
                LN_CHECK_EQ(pub->publish(seq), LN_OK);
            std::this_thread::sleep_for(std::chrono::microseconds(200));
        }
    });
    Forwarder *watched = b.get(); // outlives the watcher
    std::thread watcher([&] {
        while (!stop)
            for (const auto &s : watched->stats())
                LN_CHECK(s.token != 0);
    });
    LN_CHECK(wait_until([&] {
        for (auto &p : pairs)
            if (p.dst->newest() < 3)
                return false;
        return true;
    }));
    a.reset(); // b keeps sending to a's closed port and receiving from nobody
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    stop = true;
    watcher.join();
    b.reset();
    publisher.join();
}

} // namespace

int main()
{
    LN_TEST_RUN(test_refused_specs);
    LN_TEST_RUN(test_replace);
    LN_TEST_RUN(test_remove);
    LN_TEST_RUN(test_destroy_while_running);
    LN_TEST_EXIT();
}
