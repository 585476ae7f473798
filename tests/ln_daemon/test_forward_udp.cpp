// End-to-end tests of UDP forwarding on 127.0.0.1: a "sender host" ring and a "receiver
// host" ring, two Forwarders on ephemeral ports.  Small samples keep their numbers and
// timestamps; 8 MiB and 64 MiB samples arrive byte for byte; a relay that loses every k-th
// datagram costs exactly the samples it hits and never more memory than the bound; crafted
// duplicates, reordered and broken datagrams are counted where they belong.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <set>
#include <vector>

#include "forward_test.hpp"
#include "forward_wire.hpp"

using namespace fwdtest;
using lnd::fwd::Forwarder;
using lnd::fwd::Level;
using lnd::fwd::Options;
using lnd::fwd::Transport;

namespace {

constexpr uint64_t kToken = 0x1111222233334444ull;

// A datagram as a sender would make it, with fragment `index` of sample `seq` (pattern
// bytes) cut into chunks of `chunk`.
std::vector<uint8_t> datagram(uint64_t token, uint64_t seq, uint64_t size, uint16_t chunk,
                              uint32_t index)
{
    std::vector<uint8_t> sample(size);
    fill(sample.data(), size, seq);
    lnd::fwd::wire::Fragment f;
    f.token = token;
    f.seq = seq;
    f.timestamp_ns = stamp(seq);
    f.sample_size = size;
    f.chunk_size = chunk;
    f.count = static_cast<uint32_t>(lnd::fwd::wire::fragment_count(size, chunk));
    f.index = index;
    uint64_t length = lnd::fwd::wire::fragment_length(size, chunk, index);
    std::vector<uint8_t> d(lnd::fwd::wire::kFragmentHeaderSize + length);
    lnd::fwd::wire::encode_fragment_header(d.data(), f);
    std::memcpy(d.data() + lnd::fwd::wire::kFragmentHeaderSize,
                sample.data() + static_cast<uint64_t>(index) * chunk, length);
    return d;
}

// Every sample the reader can still get, checked against its pattern and timestamp.
std::vector<uint64_t> drain(Reader &reader)
{
    std::vector<uint64_t> seqs;
    while (reader.read(0) == LN_OK) {
        seqs.push_back(reader.info.seq);
        LN_CHECK_EQ(reader.info.timestamp_ns, stamp(reader.info.seq));
        LN_CHECK(matches(reader.buf.data(), reader.buf.size(), reader.info.seq));
    }
    return seqs;
}

void small_samples_keep_seq_and_timestamp(unsigned spin_us)
{
    TestRing src(64, 8), dst(64, 1024);
    Options o = local_options();
    o.spin_us = spin_us;
    Forwarder rx(o), tx(o);
    CHECK_STR(rx.set_recv(recv_spec(kToken, dst, Transport::udp)).text, "");
    CHECK_STR(tx.set_send(send_spec(kToken, src, Transport::udp, rx.data_port())).text, "");
    Reader reader(dst);
    Publisher pub(src);
    std::vector<double> one_way_us;
    for (uint64_t seq = 1; seq <= 1000; ++seq) {
        auto t0 = std::chrono::steady_clock::now();
        LN_CHECK_EQ(pub.publish(seq), LN_OK);
        LN_CHECK_EQ(reader.read(30), LN_OK);
        one_way_us.push_back(
            std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0)
                .count());
        LN_CHECK_EQ(reader.info.seq, seq);
        LN_CHECK_EQ(reader.info.timestamp_ns, stamp(seq));
        LN_CHECK_EQ(reader.info.overruns, 0);
        LN_CHECK(matches(reader.buf.data(), reader.buf.size(), seq));
        if (ln_test_failures)
            break;
    }
    std::sort(one_way_us.begin(), one_way_us.end());
    if (!one_way_us.empty()) // information only: a loaded machine must not fail the test
        std::printf("    64 B publish -> forwarded sample read: median %.1f us, p99 %.1f us\n",
                    one_way_us[one_way_us.size() / 2], one_way_us[one_way_us.size() * 99 / 100]);
    // The sender counts a sample after its send returned, which may be after it arrived.
    LN_CHECK(wait_until([&] { return stats_of(tx, kToken, true).samples == 1000; }));
    auto s = stats_of(tx, kToken, true);
    LN_CHECK_EQ(s.samples, 1000);
    LN_CHECK_EQ(s.drops, 0);
    LN_CHECK_EQ(s.bytes, 64000);
    LN_CHECK(s.connected);
    CHECK_STR(s.ring, src.name());
    CHECK_STR(s.peer, "127.0.0.1:" + std::to_string(rx.data_port()));
    // Counted right after the write into the ring, which the reader may see first.
    LN_CHECK(wait_until([&] { return stats_of(rx, kToken, false).samples == 1000; }));
    auto r = stats_of(rx, kToken, false);
    LN_CHECK_EQ(r.samples, 1000);
    LN_CHECK_EQ(r.bytes, 64000);
    LN_CHECK_EQ(r.drops + r.stale + r.invalid, 0);
    CHECK_STR(r.ring, dst.name());
    LN_CHECK(r.peer.rfind("127.0.0.1:", 0) == 0);
    LN_CHECK_EQ(rx.totals().malformed + rx.totals().unknown_stream, 0);
}

// Publishes big samples until one arrives whole (a loaded loopback may drop datagrams,
// which only costs that sample) and compares it byte for byte.  The socket buffers are
// what an unprivileged daemon gets by default (net.core.rmem_max), far smaller than the
// sample: the sender's rate limit is what lets the receiver keep up.
void big_sample(uint64_t size, size_t payload)
{
    TestRing src(size, 2), dst(size, 2);
    Options ro = local_options(), so = local_options();
    so.udp_payload = payload;
    so.udp_max_rate = 50e6;
    ro.socket_buffer = so.socket_buffer = 212992;
    Forwarder rx(ro), tx(so);
    CHECK_STR(rx.set_recv(recv_spec(kToken, dst, Transport::udp)).text, "");
    CHECK_STR(tx.set_send(send_spec(kToken, src, Transport::udp, rx.data_port())).text, "");
    Reader reader(dst);
    Publisher pub(src);
    bool arrived = false;
    uint64_t seq = 1;
    for (; seq <= 20 && !arrived; ++seq) {
        LN_CHECK_EQ(pub.publish(seq), LN_OK);
        // Either it arrives, or the receiver gives it up when its fragments stop coming.
        wait_until([&] {
            auto r = stats_of(rx, kToken, false);
            return r.samples + r.drops >= seq || stats_of(tx, kToken, true).drops > 0;
        });
        if (reader.read(0) == LN_OK) {
            arrived = true;
            LN_CHECK_EQ(reader.info.seq, seq);
            LN_CHECK_EQ(reader.info.timestamp_ns, stamp(seq));
            LN_CHECK(matches(reader.buf.data(), reader.buf.size(), seq));
        }
    }
    LN_CHECK(arrived);
    std::printf("    %llu MiB in %zu-byte fragments: arrived whole at attempt %llu\n",
                static_cast<unsigned long long>(size >> 20), payload,
                static_cast<unsigned long long>(seq - 1));
    LN_CHECK(rx.totals().reassembly_peak <= ro.udp_reassembly_bytes);
    LN_CHECK(wait_until([&] { return rx.totals().reassembly_bytes == 0; }));
}

void test_small_samples_keep_seq_and_timestamp() { small_samples_keep_seq_and_timestamp(0); }

// The same with sender and receiver polling before they sleep (--spin-us).
void test_small_samples_polling() { small_samples_keep_seq_and_timestamp(200); }

void test_8mib_sample() { big_sample(8u << 20, 1400); }

void test_64mib_sample()
{
    big_sample(64u << 20, 1400);
    big_sample(64u << 20, 60000); // a receiver with the default 1400 takes any chunk size
}

// Every 13th datagram is lost on the way; samples of 10 fragments.  Exactly the samples
// hit lose, each counted once in drops; the reassembly budget (two samples) is what limits
// memory when three incomplete samples follow each other.
void test_lossy_link()
{
    constexpr uint16_t kChunk = 1000;
    constexpr uint64_t kFragments = 10, kSize = kChunk * kFragments - 500, kEvery = 13;
    std::vector<uint64_t> complete; // sequence numbers (from 1) no lost datagram belongs to
    uint64_t samples = 0;
    for (uint64_t j = 0; j < 60; ++j) {
        bool hit = false;
        for (uint64_t n = j * kFragments + 1; n <= (j + 1) * kFragments; ++n)
            hit |= n % kEvery == 0;
        if (!hit) {
            complete.push_back(j + 1);
            samples = j + 1; // end on a complete sample: every loss before it is final
        }
    }
    TestRing src(kSize, 4), dst(kSize, 128);
    Options ro = local_options(), so = local_options();
    ro.udp_reassembly_bytes = 2 * (kSize + 64);
    ro.udp_max_incomplete = 4;
    so.udp_payload = kChunk;
    Forwarder rx(ro), tx(so);
    UdpRelay relay(rx.data_port(), [](uint64_t n) { return n % kEvery == 0 ? 0 : 1; });
    CHECK_STR(rx.set_recv(recv_spec(kToken, dst, Transport::udp)).text, "");
    CHECK_STR(tx.set_send(send_spec(kToken, src, Transport::udp, relay.port())).text, "");
    Reader reader(dst);
    Publisher pub(src);
    for (uint64_t seq = 1; seq <= samples; ++seq) {
        LN_CHECK_EQ(pub.publish(seq), LN_OK);
        LN_CHECK(wait_until([&] { return relay.seen() >= seq * kFragments; }));
    }
    LN_CHECK(wait_until([&] {
        auto r = stats_of(rx, kToken, false);
        return r.samples + r.drops >= samples;
    }));
    auto r = stats_of(rx, kToken, false);
    LN_CHECK_EQ(r.samples, complete.size());
    LN_CHECK_EQ(r.drops, samples - complete.size());
    LN_CHECK_EQ(r.stale + r.invalid, 0);
    LN_CHECK(drain(reader) == complete);
    auto t = rx.totals();
    LN_CHECK(t.reassembly_peak <= ro.udp_reassembly_bytes);
    LN_CHECK(t.reassembly_peak >= 2 * kSize); // the bound, not the count, was the limit
    LN_CHECK_EQ(t.reassembly_bytes, 0);
    auto s = stats_of(tx, kToken, true);
    LN_CHECK_EQ(s.samples, samples);
    LN_CHECK_EQ(s.drops, 0);
}

// Every datagram arrives twice.  Unprotected (level none), a single-fragment sample is the
// whole sample, so its copy counts as stale, and copies of fragments are ignored; protected,
// every copy is a replay the window rejects before anything else looks at it.  The ring gets
// every sample once.
void duplicated_datagrams(Level level)
{
    TestRing src1(64, 4), dst1(64, 256), src2(5000, 4), dst2(5000, 256);
    Forwarder rx(local_options()), tx(local_options());
    UdpRelay relay(rx.data_port(), [](uint64_t) { return 2; });
    CHECK_STR(rx.set_recv(recv_spec(1, dst1, Transport::udp, level)).text, "");
    CHECK_STR(rx.set_recv(recv_spec(2, dst2, Transport::udp, level)).text, "");
    CHECK_STR(tx.set_send(send_spec(1, src1, Transport::udp, relay.port(), level)).text, "");
    CHECK_STR(tx.set_send(send_spec(2, src2, Transport::udp, relay.port(), level)).text, "");
    Reader reader1(dst1), reader2(dst2);
    Publisher pub1(src1), pub2(src2);
    for (uint64_t seq = 1; seq <= 200; ++seq) {
        LN_CHECK_EQ(pub1.publish(seq), LN_OK);
        LN_CHECK_EQ(pub2.publish(seq), LN_OK);
        LN_CHECK(wait_until([&] { return dst1.newest() >= seq && dst2.newest() >= seq; }));
    }
    const bool none = level == Level::none;
    const uint64_t fragments = lnd::fwd::wire::fragment_count(5000, Options().udp_payload);
    LN_CHECK(wait_until([&] {
        auto a = stats_of(rx, 1, false), b = stats_of(rx, 2, false);
        return none ? a.stale >= 200 : a.rejected >= 200 && b.rejected >= 200 * fragments;
    }));
    std::vector<uint64_t> all(200);
    for (uint64_t i = 0; i < 200; ++i)
        all[i] = i + 1;
    LN_CHECK(drain(reader1) == all);
    LN_CHECK(drain(reader2) == all);
    auto r1 = stats_of(rx, 1, false), r2 = stats_of(rx, 2, false);
    LN_CHECK_EQ(r1.samples, 200);
    LN_CHECK_EQ(r1.stale, none ? 200 : 0);
    LN_CHECK_EQ(r1.rejected, none ? 0 : 200);
    LN_CHECK_EQ(r2.samples, 200);
    LN_CHECK_EQ(r2.stale + r2.drops + r2.invalid, 0);
    LN_CHECK_EQ(r2.rejected, none ? 0 : 200 * fragments);
}

void test_duplicated_datagrams() { duplicated_datagrams(Level::none); }
void test_duplicated_datagrams_are_replays() { duplicated_datagrams(Level::authenticate); }

// Crafted datagrams in a chosen order: older and repeated samples are stale, fragments may
// come in any order and twice, an incomplete sample overtaken by a newer complete one is
// dropped, and the ring only ever gets increasing numbers.
void test_reordered_datagrams()
{
    TestRing small(64, 64), big(3000, 64);
    Forwarder rx(local_options());
    CHECK_STR(rx.set_recv(recv_spec(1, small, Transport::udp, Level::none)).text, "");
    CHECK_STR(rx.set_recv(recv_spec(2, big, Transport::udp, Level::none)).text, "");
    Reader small_reader(small), big_reader(big);
    UdpSocket sock;
    auto send = [&](const std::vector<uint8_t> &d) {
        sock.send_to(rx.data_port(), d.data(), d.size());
    };

    for (uint64_t seq : {10, 8, 10, 12, 11, 13})
        send(datagram(1, seq, 64, 1400, 0));
    LN_CHECK(wait_until([&] { return stats_of(rx, 1, false).samples == 3; }));
    LN_CHECK(drain(small_reader) == (std::vector<uint64_t>{10, 12, 13}));
    auto r = stats_of(rx, 1, false);
    LN_CHECK_EQ(r.samples, 3);
    LN_CHECK_EQ(r.stale, 3);

    struct Step {
        uint64_t seq;
        uint32_t index;
    };
    const Step steps[] = {
        {20, 2}, {20, 0}, {20, 0}, {20, 1}, // out of order, one twice: 20 complete
        {20, 1},                            // late copy: ignored
        {15, 0}, {15, 1},                   // older than the ring's newest: stale once
        {22, 0}, {22, 1},                   // 22 in progress ...
        {21, 0}, {21, 1}, {21, 2},          // ... while the older 21 completes
        {22, 2},                            // 22 complete
        {24, 0}, {24, 1},                   // 24 in progress ...
        {23, 2}, {23, 1}, {23, 0},          // ... 23 completes ...
        {25, 0}, {25, 1}, {25, 2},          // ... 25 completes: 24 is dropped
    };
    for (const Step &s : steps)
        send(datagram(2, s.seq, 3000, 1000, s.index));
    LN_CHECK(wait_until([&] { return stats_of(rx, 2, false).samples == 5; }));
    LN_CHECK(drain(big_reader) == (std::vector<uint64_t>{20, 21, 22, 23, 25}));
    r = stats_of(rx, 2, false);
    LN_CHECK_EQ(r.samples, 5);
    LN_CHECK_EQ(r.stale, 1);
    LN_CHECK_EQ(r.drops, 1);
    LN_CHECK_EQ(r.invalid, 0);
    LN_CHECK_EQ(rx.totals().reassembly_bytes, 0);
}

// Datagrams that are not ours, or not for any stream here, or wrong for their stream, are
// counted where they belong, and the stream goes on working.
void test_garbage_datagrams()
{
    TestRing ring(3000, 8), tcp_ring(3000, 8);
    Forwarder rx(local_options());
    CHECK_STR(rx.set_recv(recv_spec(7, ring, Transport::udp, Level::none)).text, "");
    CHECK_STR(rx.set_recv(recv_spec(8, tcp_ring, Transport::tcp, Level::none)).text, "");
    UdpSocket sock;
    auto send = [&](std::vector<uint8_t> d) { sock.send_to(rx.data_port(), d.data(), d.size()); };
    namespace wire = lnd::fwd::wire;

    send(std::vector<uint8_t>(10, 0xab)); // too short
    auto d = datagram(7, 1, 3000, 1000, 0);
    d[0] = 'X'; // magic
    send(d);
    d = datagram(7, 1, 3000, 1000, 0);
    d[4] = 1; // version (before frame trailers)
    send(d);
    d = datagram(7, 1, 3000, 1000, 0);
    d[5] = static_cast<uint8_t>(wire::Kind::hello); // kind
    send(d);
    send(datagram(9, 1, 3000, 1000, 0)); // no such stream
    send(datagram(8, 1, 3000, 1000, 0)); // a TCP stream
    send(datagram(7, 1, 2999, 1000, 0)); // sample size
    d = datagram(7, 1, 3000, 1000, 0);
    d[40] = 3; // index 3 of 3
    send(d);
    d = datagram(7, 1, 3000, 1000, 1);
    d.pop_back(); // chunk shorter than its index needs
    send(d);
    d = datagram(7, 1, 3000, 1000, 0);
    d[44] = 4; // count does not fit size and chunk
    send(d);
    send(datagram(7, 0, 3000, 1000, 0)); // sequence number 0
    LN_CHECK(wait_until([&] { return stats_of(rx, 7, false).invalid >= 5; }));

    Reader reader(ring);
    for (uint32_t i = 0; i < 3; ++i)
        send(datagram(7, 5, 3000, 1000, i));
    LN_CHECK(wait_until([&] { return stats_of(rx, 7, false).samples == 1; }));
    LN_CHECK(drain(reader) == std::vector<uint64_t>{5});
    auto t = rx.totals();
    LN_CHECK_EQ(t.malformed, 4);
    LN_CHECK_EQ(t.unknown_stream, 2);
    auto r = stats_of(rx, 7, false);
    LN_CHECK_EQ(r.invalid, 5);
    LN_CHECK_EQ(r.samples, 1);
    LN_CHECK_EQ(r.drops + r.stale, 0);
    LN_CHECK(r.last_error.find("invalid datagram") != std::string::npos);
    LN_CHECK_EQ(stats_of(rx, 8, false).invalid, 0);
}

} // namespace

int main()
{
    LN_TEST_RUN(test_small_samples_keep_seq_and_timestamp);
    LN_TEST_RUN(test_small_samples_polling);
    LN_TEST_RUN(test_8mib_sample);
    LN_TEST_RUN(test_64mib_sample);
    LN_TEST_RUN(test_lossy_link);
    LN_TEST_RUN(test_duplicated_datagrams);
    LN_TEST_RUN(test_duplicated_datagrams_are_replays);
    LN_TEST_RUN(test_reordered_datagrams);
    LN_TEST_RUN(test_garbage_datagrams);
    LN_TEST_EXIT();
}
