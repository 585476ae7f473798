// Unit tests of one pull topic served on a real UDP port on 127.0.0.1 (the kernel picks the
// port) from a real ring: every reply rule (sync, in history, too old, no sample yet, parked
// then answered on publish, far future, parked seqs the publisher skipped), duplicate
// nonces, the parked table's overflow and expiry, PIT tokens, HMAC signatures, a ring that
// appears late, and bad packets counted per port while the topic keeps answering.
#include <cstdint>
#include <memory>
#include <string>
#include <unistd.h>
#include <vector>

#include "forward_test.hpp"
#include "pull_port.hpp"
#include "pull_test.hpp"
#include "pull_topic.hpp"

using namespace lnd;
using fwdtest::Publisher;
using fwdtest::TestRing;
using fwdtest::wait_until;
using pulltest::Consumer;
using pulltest::Reply;

namespace {

constexpr uint64_t kSize = 64;
const std::string kName = "/ln/unit/arm.state";

PullConfig config_for(const std::string &ring, uint32_t history, const std::string &key = "")
{
    PullConfig c;
    c.ring = ring;
    c.md_name = "test/fwd";
    c.layout_hash = fwdtest::kHash;
    c.message_size = kSize;
    c.uri = kName;
    c.name = pulltest::name_of(kName);
    c.history = history;
    c.freshness_ms = 1000;
    c.signature = key.empty() ? LN_NDN_SIG_DIGEST_SHA256 : LN_NDN_SIG_HMAC_SHA256;
    c.key = key;
    return c;
}

// A topic served on its own port from its own ring, with a consumer pointed at it.
struct Served {
    explicit Served(uint32_t history, const std::string &key = "") : ring(kSize, 8), pub(ring)
    {
        CHECK_STR(PullPort::open("127.0.0.1", 0, port).text, "");
        topic = std::make_unique<PullTopic>(config_for(ring.name(), history, key), "unit");
        port->attach(topic.get());
        topic->start(port->fd());
        consumer = std::make_unique<Consumer>(port->port());
    }
    ~Served() { port->detach(topic.get()); } // before the topic goes, then the port

    void publish_to(uint64_t last)
    {
        for (uint64_t s = topic->status().latest_seq + 1; s <= last; ++s)
            LN_CHECK_EQ(pub.publish(s), LN_OK);
        LN_CHECK(wait_until([&] { return topic->status().latest_seq == last; }));
    }
    PullTopicCounters counters() const { return topic->status().counters; }
    std::string seq_uri(uint64_t s) const { return kName + "/seq=" + std::to_string(s); }

    TestRing ring;
    Publisher pub;
    std::unique_ptr<PullPort> port;
    std::unique_ptr<PullTopic> topic;
    std::unique_ptr<Consumer> consumer;
};

// A Data reply carrying sample `seq` whole, with the producer's newest seq `latest`.
void check_sample(const Reply &r, uint64_t seq, uint64_t latest)
{
    LN_CHECK(!r.nack());
    LN_CHECK_EQ(r.content.latest_seq, latest);
    LN_CHECK_EQ(r.content.publish_us, uint64_t(fwdtest::stamp(seq)) / 1000);
    LN_CHECK_EQ(r.content.payload.size, kSize);
    LN_CHECK(r.content.payload.size == kSize &&
             fwdtest::matches(r.content.payload.data, kSize, seq));
    ln_ndn_signer digest{};
    digest.type = LN_NDN_SIG_DIGEST_SHA256;
    LN_CHECK_EQ(ln_ndn_verify(&r.pkt.data, &digest), LN_NDN_OK);
}

void test_no_sample_yet()
{
    Served s(8);
    s.consumer->interest(kName + "/sync", 1);
    Reply r;
    LN_CHECK(s.consumer->receive(r));
    LN_CHECK(r.nack());
    CHECK_STR(r.uri, kName + "/sync");
    LN_CHECK_EQ(r.content.latest_seq, 0);
    LN_CHECK(r.content.payload.data == nullptr);
    s.consumer->interest(s.seq_uri(1), 2);
    LN_CHECK(s.consumer->receive(r));
    LN_CHECK(r.nack());
    LN_CHECK_EQ(r.content.latest_seq, 0);
    PullTopicCounters c = s.counters();
    LN_CHECK_EQ(c.interests, 2);
    LN_CHECK_EQ(c.syncs, 1);
    LN_CHECK_EQ(c.nacks, 2);
    LN_CHECK_EQ(c.data, 0);
}

void test_sync_and_history()
{
    Served s(4);
    s.publish_to(10);
    Reply r;
    s.consumer->interest(kName + "/sync", 1);
    LN_CHECK(s.consumer->receive(r));
    CHECK_STR(r.uri, kName + "/sync/seq=10");
    LN_CHECK_EQ(r.pkt.data.freshness_ms, 0);
    check_sample(r, 10, 10);
    LN_CHECK(r.content.period_us > 0); // the stamps are 1 µs apart
    LN_CHECK_EQ(r.content.period_us, 1);

    s.consumer->interest(s.seq_uri(7), 2); // the oldest of a history of 4
    LN_CHECK(s.consumer->receive(r));
    CHECK_STR(r.uri, s.seq_uri(7));
    LN_CHECK_EQ(r.pkt.data.freshness_ms, 1000);
    check_sample(r, 7, 10);

    s.consumer->interest(s.seq_uri(6), 3); // too old: NACK with the newest
    LN_CHECK(s.consumer->receive(r));
    CHECK_STR(r.uri, s.seq_uri(6));
    LN_CHECK(r.nack());
    LN_CHECK_EQ(r.pkt.data.freshness_ms, 0);
    LN_CHECK_EQ(r.content.latest_seq, 10);

    s.consumer->interest(s.seq_uri(15), 4); // beyond newest + history: NACK
    LN_CHECK(s.consumer->receive(r));
    LN_CHECK(r.nack());
    LN_CHECK_EQ(r.content.latest_seq, 10);
    CHECK_STR(r.uri, s.seq_uri(15));

    PullTopicCounters c = s.counters();
    LN_CHECK_EQ(c.interests, 4);
    LN_CHECK_EQ(c.syncs, 1);
    LN_CHECK_EQ(c.data, 2);
    LN_CHECK_EQ(c.nacks, 2);
    LN_CHECK_EQ(c.parked, 0);
}

void test_parked_until_published()
{
    Served s(4);
    s.publish_to(3);
    s.consumer->interest(s.seq_uri(4), 1);
    s.consumer->interest(s.seq_uri(7), 2); // newest + history: still parked
    LN_CHECK(wait_until([&] { return s.counters().parked == 2; }));
    LN_CHECK(!s.consumer->pending());
    LN_CHECK_EQ(s.pub.publish(4), LN_OK);
    Reply r;
    LN_CHECK(s.consumer->receive(r));
    CHECK_STR(r.uri, s.seq_uri(4));
    LN_CHECK_EQ(r.pkt.data.freshness_ms, 1000);
    check_sample(r, 4, 4);
    // 5 and 6 are skipped (a gap): the Interest for 7 is answered by 7 itself
    LN_CHECK_EQ(s.pub.publish(7), LN_OK);
    LN_CHECK(s.consumer->receive(r));
    CHECK_STR(r.uri, s.seq_uri(7));
    check_sample(r, 7, 7);
    PullTopicCounters c = s.counters();
    LN_CHECK_EQ(c.data, 2);
    LN_CHECK_EQ(c.nacks, 0);
    LN_CHECK_EQ(c.expired, 0);
}

void test_parked_passed_over()
{
    Served s(8);
    s.publish_to(2);
    s.consumer->interest(s.seq_uri(3), 1);
    LN_CHECK(wait_until([&] { return s.counters().parked == 1; }));
    LN_CHECK_EQ(s.pub.publish(5), LN_OK); // 3 never comes
    Reply r;
    LN_CHECK(s.consumer->receive(r));
    CHECK_STR(r.uri, s.seq_uri(3));
    LN_CHECK(r.nack());
    LN_CHECK_EQ(r.content.latest_seq, 5);
    LN_CHECK_EQ(s.counters().nacks, 1);
}

void test_duplicate_nonce()
{
    Served s(8);
    s.publish_to(5);
    s.consumer->interest(s.seq_uri(4), 77);
    s.consumer->interest(s.seq_uri(4), 77); // the same Interest again: dropped
    s.consumer->interest(s.seq_uri(4), 78); // a retransmission (new nonce): answered
    s.consumer->interest(s.seq_uri(5), 77); // another name with the same nonce: answered
    Reply r;
    LN_CHECK(s.consumer->receive(r));
    CHECK_STR(r.uri, s.seq_uri(4));
    LN_CHECK(s.consumer->receive(r));
    CHECK_STR(r.uri, s.seq_uri(4));
    LN_CHECK(s.consumer->receive(r));
    CHECK_STR(r.uri, s.seq_uri(5)); // not a third reply for seq 4
    PullTopicCounters c = s.counters();
    LN_CHECK_EQ(c.interests, 4);
    LN_CHECK_EQ(c.duplicates, 1);
    LN_CHECK_EQ(c.data, 3);
}

void test_parked_overflow_and_retransmission()
{
    Served s(2 * kPullParked); // every seq asked for is within newest + history
    s.publish_to(1);
    for (uint64_t k = 0; k < kPullParked; ++k)
        s.consumer->interest(s.seq_uri(2 + k), uint32_t(100 + k));
    // a retransmission of a parked seq from the same consumer takes its own entry's place
    s.consumer->interest(s.seq_uri(2), 200);
    LN_CHECK(wait_until([&] { return s.counters().parked == kPullParked + 1; }));
    s.consumer->interest(s.seq_uri(2 + kPullParked), 300); // the table is full: NACK
    Reply r;
    LN_CHECK(s.consumer->receive(r));
    CHECK_STR(r.uri, s.seq_uri(2 + kPullParked));
    LN_CHECK(r.nack());
    LN_CHECK_EQ(r.content.latest_seq, 1);
    LN_CHECK_EQ(s.counters().overflow, 1);
    for (uint64_t k = 0; k < kPullParked; ++k) {
        LN_CHECK_EQ(s.pub.publish(2 + k), LN_OK);
        LN_CHECK(s.consumer->receive(r));
        CHECK_STR(r.uri, s.seq_uri(2 + k)); // one reply per seq, also for seq 2
    }
    PullTopicCounters c = s.counters();
    LN_CHECK_EQ(c.data, kPullParked);
    LN_CHECK_EQ(c.nacks, 1);
}

void test_parked_expiry()
{
    Served s(8);
    s.publish_to(1);
    s.consumer->interest(s.seq_uri(2), 1, 30); // a 30 ms lifetime
    LN_CHECK(wait_until([&] { return s.counters().expired == 1; }));
    LN_CHECK_EQ(s.counters().parked, 1);
    s.publish_to(2);
    s.consumer->interest(kName + "/sync", 2);
    Reply r;
    LN_CHECK(s.consumer->receive(r)); // the expired Interest got nothing: this is the sync
    CHECK_STR(r.uri, kName + "/sync/seq=2");
    PullTopicCounters c = s.counters();
    LN_CHECK_EQ(c.data, 1);
    LN_CHECK_EQ(c.nacks, 0);
}

void test_pit_token_and_hmac()
{
    const std::string key = "a shared secret";
    Served s(8, key);
    s.publish_to(3);
    s.consumer->interest(s.seq_uri(3), 1, 4000, "tok-123");
    Reply r;
    LN_CHECK(s.consumer->receive(r));
    LN_CHECK(r.pkt.lp);
    LN_CHECK(std::string(reinterpret_cast<const char *>(r.pkt.pit_token.data),
                         r.pkt.pit_token.size) == "tok-123");
    CHECK_STR(r.uri, s.seq_uri(3));
    LN_CHECK_EQ(r.pkt.data.signature_type, LN_NDN_SIG_HMAC_SHA256);
    ln_ndn_signer hmac{};
    hmac.type = LN_NDN_SIG_HMAC_SHA256;
    hmac.key = reinterpret_cast<const uint8_t *>(key.data());
    hmac.key_size = key.size();
    LN_CHECK_EQ(ln_ndn_verify(&r.pkt.data, &hmac), LN_NDN_OK);
    hmac.key_size = key.size() - 1;
    LN_CHECK(ln_ndn_verify(&r.pkt.data, &hmac) != LN_NDN_OK);
    // parked, then answered by the ring thread: the token comes back as well
    s.consumer->interest(s.seq_uri(4), 2, 4000, "t2");
    LN_CHECK(wait_until([&] { return s.counters().parked == 1; }));
    LN_CHECK_EQ(s.pub.publish(4), LN_OK);
    LN_CHECK(s.consumer->receive(r));
    LN_CHECK(r.pkt.lp);
    LN_CHECK_EQ(r.pkt.pit_token.size, 2);
    CHECK_STR(r.uri, s.seq_uri(4));
    // a bare Interest gets a bare reply
    s.consumer->interest(s.seq_uri(4), 3);
    LN_CHECK(s.consumer->receive(r));
    LN_CHECK(!r.pkt.lp);
}

void test_bad_packets()
{
    Served s(8);
    s.publish_to(2);
    const uint8_t garbage[] = {0x05, 0xff, 0x01};                        // cut off
    const uint8_t critical[] = {0x05, 0x08, 0x07, 0x03, 0x08, 0x01, 'x', // unknown type 13
                                0x0d, 0x01, 0x00};
    s.consumer->raw(garbage, sizeof garbage);
    s.consumer->raw(critical, sizeof critical);
    s.consumer->raw("", 0);
    // Data at the producer: not an Interest
    std::vector<uint8_t> name = pulltest::name_of(kName + "/seq=1");
    ln_ndn_data d{};
    d.name = {name.data(), name.size()};
    ln_ndn_signer digest{};
    uint8_t data[512];
    int n = ln_ndn_encode_data(data, sizeof data, &d, &digest);
    LN_CHECK(n > 0);
    s.consumer->raw(data, static_cast<size_t>(n));
    // names nobody serves
    s.consumer->interest("/ln/unit/other/seq=1", 1);
    s.consumer->interest(kName, 2);
    s.consumer->interest(kName + "/seq=1/more", 3);
    s.consumer->interest(kName + "/latest", 4);
    // a datagram larger than the receive buffer
    std::vector<uint8_t> big(kPullRxBytes + 100, 0x05);
    s.consumer->raw(big.data(), big.size());
    // and the topic still answers
    s.consumer->interest(kName + "/sync", 5);
    Reply r;
    LN_CHECK(s.consumer->receive(r));
    CHECK_STR(r.uri, kName + "/sync/seq=2");
    PullPortStatus p = s.port->status();
    LN_CHECK_EQ(p.counters.packets, 10);
    LN_CHECK_EQ(p.counters.bad, 4);
    LN_CHECK_EQ(p.counters.other, 1);
    LN_CHECK_EQ(p.counters.unknown, 4);
    PullTopicCounters c = s.counters();
    LN_CHECK_EQ(c.interests, 1);
    LN_CHECK_EQ(c.data, 1);
}

// A sample published before the topic was served is served at once (sync and by seq),
// and the next one follows it into the history.
void test_published_before_served()
{
    TestRing ring(kSize, 8);
    Publisher pub(ring);
    LN_CHECK_EQ(pub.publish(1), LN_OK);
    LN_CHECK_EQ(pub.publish(2), LN_OK);
    std::unique_ptr<PullPort> port;
    CHECK_STR(PullPort::open("127.0.0.1", 0, port).text, "");
    auto topic = std::make_unique<PullTopic>(config_for(ring.name(), 8), "unit early");
    port->attach(topic.get());
    topic->start(port->fd());
    LN_CHECK(wait_until([&] { return topic->status().latest_seq == 2; })); // the newest
    Consumer consumer(port->port());
    consumer.interest(kName + "/sync", 1);
    Reply r;
    LN_CHECK(consumer.receive(r));
    check_sample(r, 2, 2);
    consumer.interest(kName + "/seq=1", 2); // older than the seed: never read, so a NACK
    LN_CHECK(consumer.receive(r));
    LN_CHECK(r.nack());
    LN_CHECK_EQ(r.content.latest_seq, 2);
    LN_CHECK_EQ(pub.publish(3), LN_OK);
    LN_CHECK(wait_until([&] { return topic->status().latest_seq == 3; }));
    consumer.interest(kName + "/seq=2", 3); // the seed stays in the history
    LN_CHECK(consumer.receive(r));
    check_sample(r, 2, 3);
    consumer.interest(kName + "/seq=3", 4);
    LN_CHECK(consumer.receive(r));
    check_sample(r, 3, 3);
    port->detach(topic.get());
}

void test_ring_appears_later()
{
    const std::string ring = "/ln.pulltest" + std::to_string(::getpid()) + ".1.0";
    ln_ring_admin_unlink(ring.c_str());
    std::unique_ptr<PullPort> port;
    CHECK_STR(PullPort::open("127.0.0.1", 0, port).text, "");
    auto topic = std::make_unique<PullTopic>(config_for(ring, 8), "unit late");
    port->attach(topic.get());
    topic->start(port->fd());
    LN_CHECK(topic->status().last_error.find("cannot open ring '" + ring + "'") !=
             std::string::npos);
    ln_ring_admin *admin = nullptr;
    LN_CHECK_EQ(
        ln_ring_admin_create(&admin, ring.c_str(), "t", "test/fwd", fwdtest::kHash, kSize, 4),
        LN_OK);
    LN_CHECK(wait_until([&] { return topic->status().last_error.empty(); }));
    ln_ring_tap *tap = nullptr;
    LN_CHECK_EQ(ln_ring_tap_open(&tap, ring.c_str(), fwdtest::kHash, kSize, LN_TAP_NEWEST), LN_OK);
    uint8_t buf[kSize];
    fwdtest::fill(buf, kSize, 1);
    LN_CHECK_EQ(ln_ring_tap_inject(tap, buf, 1, fwdtest::stamp(1)), LN_OK);
    LN_CHECK(wait_until([&] { return topic->status().latest_seq == 1; }));
    Consumer consumer(port->port());
    consumer.interest(kName + "/seq=1", 1);
    Reply r;
    LN_CHECK(consumer.receive(r));
    check_sample(r, 1, 1);
    port->detach(topic.get());
    topic.reset();
    ln_ring_tap_close(tap);
    ln_ring_admin_close(admin);
    ln_ring_admin_unlink(ring.c_str());
}

} // namespace

int main()
{
    LN_TEST_RUN(test_no_sample_yet);
    LN_TEST_RUN(test_published_before_served);
    LN_TEST_RUN(test_sync_and_history);
    LN_TEST_RUN(test_parked_until_published);
    LN_TEST_RUN(test_parked_passed_over);
    LN_TEST_RUN(test_duplicate_nonce);
    LN_TEST_RUN(test_parked_overflow_and_retransmission);
    LN_TEST_RUN(test_parked_expiry);
    LN_TEST_RUN(test_pit_token_and_hmac);
    LN_TEST_RUN(test_bad_packets);
    LN_TEST_RUN(test_ring_appears_later);
    LN_TEST_EXIT();
}
