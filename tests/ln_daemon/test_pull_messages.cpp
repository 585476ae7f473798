// Unit tests of the PULL_* codecs: PULL_TOPIC round trip and every truncation and trailing
// byte refused, over-long strings refused, PULL_LIST field by field, the message names.
#include <cstdint>
#include <string>
#include <vector>

#include "daemon_test.hpp"
#include "pull_messages.hpp"

using namespace lnd;

namespace {

PullTopicRequest sample_request()
{
    PullTopicRequest q;
    q.topic = "arm.state";
    q.ring = "/ln.lab.1.1";
    q.md_name = "robot/joint_state";
    q.layout_hash = 0x1122334455667788u;
    q.message_size = 96;
    q.address = "10.0.0.1";
    q.port = 6363;
    q.name = "/ln/lab/arm.state";
    q.history = 64;
    q.freshness_ms = 1000;
    q.signature = 4;
    q.key = std::string("k\0ey", 4);
    return q;
}

void test_pull_topic_round_trip()
{
    proto::Writer w;
    encode_pull_topic(w, sample_request());
    const std::string &b = w.buffer();
    int accepted = 0;
    for (size_t n = 0; n < b.size(); ++n) {
        proto::Reader r(b.data(), n);
        PullTopicRequest partial;
        accepted += decode_pull_topic(r, partial);
    }
    LN_CHECK_EQ(accepted, 0);
    std::string longer = b + "x";
    proto::Reader extra(longer.data(), longer.size());
    PullTopicRequest ignored;
    LN_CHECK(!decode_pull_topic(extra, ignored));

    proto::Reader r(b.data(), b.size());
    PullTopicRequest q;
    LN_CHECK(decode_pull_topic(r, q));
    CHECK_STR(q.topic, "arm.state");
    CHECK_STR(q.ring, "/ln.lab.1.1");
    CHECK_STR(q.md_name, "robot/joint_state");
    LN_CHECK(q.layout_hash == 0x1122334455667788u);
    LN_CHECK_EQ(q.message_size, 96);
    CHECK_STR(q.address, "10.0.0.1");
    LN_CHECK_EQ(q.port, 6363);
    CHECK_STR(q.name, "/ln/lab/arm.state");
    LN_CHECK_EQ(q.history, 64);
    LN_CHECK_EQ(q.freshness_ms, 1000);
    LN_CHECK_EQ(q.signature, 4);
    LN_CHECK(q.key == std::string("k\0ey", 4));
    // the wire layout, field by field (little-endian, u32-prefixed strings)
    LN_CHECK_EQ(b.size(), 4 + 9 + 4 + 11 + 4 + 17 + 8 + 8 + 4 + 8 + 2 + 4 + 17 + 4 + 4 + 1 + 4 + 4);
}

void test_pull_topic_limits()
{
    PullTopicRequest q = sample_request();
    q.name = "/" + std::string(kMaxPullName - 1, 'n');
    proto::Writer ok;
    encode_pull_topic(ok, q);
    proto::Reader r(ok.buffer().data(), ok.buffer().size());
    PullTopicRequest out;
    LN_CHECK(decode_pull_topic(r, out)); // 1024 bytes of name are fine
    for (int field = 0; field < 3; ++field) {
        PullTopicRequest bad = sample_request();
        if (field == 0)
            bad.name += std::string(kMaxPullName, 'n');
        else if (field == 1)
            bad.key = std::string(kMaxPullKey + 1, 'k');
        else
            bad.topic = std::string(proto::kMaxName + 1, 't');
        proto::Writer w;
        encode_pull_topic(w, bad);
        proto::Reader rr(w.buffer().data(), w.buffer().size());
        LN_CHECK(!decode_pull_topic(rr, out));
    }
}

void test_topic_name_payload()
{
    proto::Writer w;
    w.str("arm.state");
    std::string topic;
    proto::Reader r(w.buffer().data(), w.buffer().size());
    LN_CHECK(decode_pull_topic_name(r, topic));
    CHECK_STR(topic, "arm.state");
    std::string longer = w.buffer() + "x";
    proto::Reader extra(longer.data(), longer.size());
    LN_CHECK(!decode_pull_topic_name(extra, topic));
    proto::Reader cut(w.buffer().data(), 3);
    LN_CHECK(!decode_pull_topic_name(cut, topic));
}

void test_pull_list()
{
    std::vector<PullPortStatus> ports(1);
    ports[0].address = "0.0.0.0";
    ports[0].port = 6363;
    ports[0].counters = {10, 2, 3, 4};
    ports[0].last_error = std::string(1000, 'e'); // cut to kMaxPullErrorText
    std::vector<PullTopicStatus> topics(2);
    topics[0].topic = "a";
    topics[0].name = "/ln/x/a";
    topics[0].ring = "/ln.x.1.1";
    topics[0].address = "0.0.0.0";
    topics[0].port = 6363;
    topics[0].history = 64;
    topics[0].latest_seq = 99;
    topics[0].counters = {1, 2, 3, 4, 5, 6, 7, 8};
    topics[1].topic = "b";
    proto::Writer w;
    encode_pull_list(w, ports, topics);
    const std::string &b = w.buffer();
    // the head by hand: u32 nports, str address, u16 port, u64 packets
    proto::Reader head(b.data(), b.size());
    LN_CHECK_EQ(head.u32(), 1);
    CHECK_STR(head.str(), "0.0.0.0");
    LN_CHECK_EQ(head.u16(), 6363);
    LN_CHECK_EQ(head.u64(), 10);

    std::vector<PullPortStatus> p;
    std::vector<PullTopicStatus> t;
    proto::Reader r(b.data(), b.size());
    LN_CHECK(decode_pull_list(r, p, t));
    LN_CHECK_EQ(p.size(), 1);
    LN_CHECK_EQ(t.size(), 2);
    if (p.size() == 1 && t.size() == 2) {
        LN_CHECK_EQ(p[0].counters.bad, 2);
        LN_CHECK_EQ(p[0].counters.unknown, 3);
        LN_CHECK_EQ(p[0].counters.other, 4);
        LN_CHECK_EQ(p[0].last_error.size(), kMaxPullErrorText);
        CHECK_STR(t[0].name, "/ln/x/a");
        CHECK_STR(t[0].ring, "/ln.x.1.1");
        LN_CHECK_EQ(t[0].port, 6363);
        LN_CHECK_EQ(t[0].history, 64);
        LN_CHECK_EQ(t[0].latest_seq, 99);
        const PullTopicCounters &c = t[0].counters;
        LN_CHECK(c.interests == 1 && c.syncs == 2 && c.data == 3 && c.nacks == 4 && c.parked == 5 &&
                 c.expired == 6 && c.duplicates == 7 && c.overflow == 8);
        CHECK_STR(t[1].topic, "b");
    }
    for (size_t n = 0; n < b.size(); ++n) {
        proto::Reader cut(b.data(), n);
        LN_CHECK(!decode_pull_list(cut, p, t));
    }
}

void test_names()
{
    CHECK_STR(pull_msg_name(static_cast<uint8_t>(proto::Msg::pull_topic)), "PULL_TOPIC");
    CHECK_STR(pull_msg_name(static_cast<uint8_t>(proto::Msg::pull_remove)), "PULL_REMOVE");
    CHECK_STR(pull_msg_name(static_cast<uint8_t>(proto::Msg::pull_status)), "PULL_STATUS");
    LN_CHECK(pull_msg_name(static_cast<uint8_t>(proto::Msg::logger_status)) == nullptr);
    LN_CHECK_EQ(static_cast<int>(proto::Msg::pull_topic), 0x51);
    LN_CHECK_EQ(static_cast<int>(proto::Msg::pull_list), 0x2a);
    LN_CHECK_EQ(static_cast<int>(proto::Err::pull_failed), 16);
}

} // namespace

int main()
{
    LN_TEST_RUN(test_pull_topic_round_trip);
    LN_TEST_RUN(test_pull_topic_limits);
    LN_TEST_RUN(test_topic_name_payload);
    LN_TEST_RUN(test_pull_list);
    LN_TEST_RUN(test_names);
    LN_TEST_EXIT();
}
