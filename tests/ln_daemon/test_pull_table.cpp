// Unit tests of the pull topic table through its requests, as the server hands them over:
// every refusal and its text, topics sharing a port, an update in place keeping the history,
// a move to another port, PULL_STATUS per instance and per topic, PULL_REMOVE closing ports
// with their last topic, and one topic served end to end through the table.
#include <arpa/inet.h>
#include <cstdint>
#include <netinet/in.h>
#include <string>
#include <sys/socket.h>
#include <unistd.h>
#include <vector>

#include "forward_test.hpp"
#include "pull_test.hpp"
#include "pulls.hpp"

using namespace lnd;
using fwdtest::Publisher;
using fwdtest::TestRing;
using fwdtest::wait_until;

namespace {

const std::string kInstance = "fwdtest" + std::to_string(::getpid()); // TestRing's namespace

PullTopicRequest request(const std::string &topic, const TestRing &ring,
                         const std::string &name = "")
{
    PullTopicRequest q;
    q.topic = topic;
    q.ring = ring.name();
    q.md_name = "test/fwd";
    q.layout_hash = ring.hash();
    q.message_size = ring.size();
    q.address = "127.0.0.1";
    q.port = 0; // the kernel picks (Pulls(true))
    q.name = name.empty() ? "/ln/unit/" + topic : name;
    q.history = 8;
    q.freshness_ms = 500;
    return q;
}

Outcome send(Pulls &pulls, proto::Msg type, const std::string &payload,
             const std::string &instance = kInstance)
{
    proto::Reader r(payload.data(), payload.size());
    return pulls.handle(Request{instance, static_cast<uint8_t>(type), 1, r});
}

Outcome configure(Pulls &pulls, const PullTopicRequest &q, const std::string &instance = kInstance)
{
    proto::Writer w;
    encode_pull_topic(w, q);
    return send(pulls, proto::Msg::pull_topic, w.buffer(), instance);
}

Outcome named(Pulls &pulls, proto::Msg type, const std::string &topic,
              const std::string &instance = kInstance)
{
    proto::Writer w;
    w.str(topic);
    return send(pulls, type, w.buffer(), instance);
}

struct List {
    std::vector<PullPortStatus> ports;
    std::vector<PullTopicStatus> topics;
};

List status(Pulls &pulls, const std::string &topic = "", const std::string &instance = kInstance)
{
    List l;
    Outcome o = named(pulls, proto::Msg::pull_status, topic, instance);
    LN_CHECK(o.kind == Outcome::Kind::reply && o.type == proto::Msg::pull_list);
    proto::Reader r(o.payload.data(), o.payload.size());
    LN_CHECK(decode_pull_list(r, l.ports, l.topics));
    return l;
}

bool is_ok(const Outcome &o) { return o.kind == Outcome::Kind::reply && o.type == proto::Msg::ok; }

// The refusal's text if `o` is a refusal with error 16, else "".
std::string refusal(const Outcome &o)
{
    if (o.kind != Outcome::Kind::error || o.code != proto::Err::pull_failed)
        return "";
    return o.text;
}

bool has(const std::string &text, const std::string &part)
{
    bool found = text.find(part) != std::string::npos;
    if (!found)
        std::fprintf(stderr, "    '%s' lacks '%s'\n", text.c_str(), part.c_str());
    return found;
}

void test_refusals()
{
    TestRing ring(64, 4);
    Pulls strict; // port 0 refused
    PullTopicRequest q = request("a", ring);
    LN_CHECK(has(refusal(configure(strict, q)), "port 0"));
    Pulls pulls(true);
    auto refused = [&](void (*change)(PullTopicRequest &), const std::string &part) {
        PullTopicRequest bad = request("a", ring);
        change(bad);
        LN_CHECK(has(refusal(configure(pulls, bad)), part));
    };
    refused([](PullTopicRequest &b) { b.message_size = 8001; },
            "message size 8001 out of range 1..8000");
    refused([](PullTopicRequest &b) { b.message_size = 8001; }, "one UDP datagram");
    refused([](PullTopicRequest &b) { b.message_size = 0; }, "message size 0");
    refused([](PullTopicRequest &b) { b.history = 0; }, "history 0 out of range 1..65536");
    refused([](PullTopicRequest &b) { b.history = 65537; }, "history 65537");
    refused([](PullTopicRequest &b) { b.name = "no-slash"; }, "is not a valid NDN URI");
    refused([](PullTopicRequest &b) { b.name = "/"; }, "has no component");
    refused([](PullTopicRequest &b) { b.ring = "/ln.other.1.1"; }, "not in the namespace");
    refused([](PullTopicRequest &b) { b.topic = ""; }, "invalid topic name");
    refused([](PullTopicRequest &b) { b.signature = 4; }, "HMAC-SHA256 needs a key");
    refused([](PullTopicRequest &b) { b.key = "k"; }, "a key is given");
    refused([](PullTopicRequest &b) { b.signature = 1; }, "unknown signature type 1");
    refused([](PullTopicRequest &b) { b.address = "localhost"; }, "not a numeric IPv4 or IPv6");
    refused(
        [](PullTopicRequest &b) {
            b.history = 65536;
            b.message_size = 8000;
        },
        "bytes for pull histories are free");
    LN_CHECK(has(refusal(named(pulls, proto::Msg::pull_remove, "nope")),
                 "no pull topic 'nope' in instance " + kInstance));
    LN_CHECK(has(refusal(named(pulls, proto::Msg::pull_status, "nope")), "no pull topic 'nope'"));
    LN_CHECK(status(pulls).ports.empty()); // nothing refused left a port open

    // a port something else holds: the address, the port and the errno text
    lnd::UniqueFd holder(::socket(AF_INET, SOCK_DGRAM, 0));
    sockaddr_in sa{};
    sa.sin_family = AF_INET;
    sa.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    LN_CHECK_EQ(::bind(holder.get(), reinterpret_cast<sockaddr *>(&sa), sizeof sa), 0);
    socklen_t len = sizeof sa;
    ::getsockname(holder.get(), reinterpret_cast<sockaddr *>(&sa), &len);
    q.port = ntohs(sa.sin_port);
    std::string text = refusal(configure(pulls, q));
    LN_CHECK(has(text, "cannot bind UDP 127.0.0.1:" + std::to_string(q.port)));
    LN_CHECK(has(text, "Address already in use"));
    // malformed: trailing bytes
    proto::Writer w;
    encode_pull_topic(w, request("a", ring));
    w.u8(0);
    LN_CHECK(send(pulls, proto::Msg::pull_topic, w.buffer()).kind == Outcome::Kind::malformed);
}

void test_shared_port_update_move_remove()
{
    TestRing ring_a(64, 8), ring_b(64, 8);
    Publisher pub(ring_a);
    Pulls pulls(true);
    LN_CHECK(is_ok(configure(pulls, request("a", ring_a))));
    LN_CHECK(is_ok(configure(pulls, request("b", ring_b))));
    // the same name on the same port: refused, naming who serves it
    std::string text = refusal(configure(pulls, request("c", ring_b, "/ln/unit/a")));
    LN_CHECK(has(text, "name '/ln/unit/a' is served already on 127.0.0.1:"));
    LN_CHECK(has(text, "by topic 'a' of instance " + kInstance));
    // also from another instance
    LN_CHECK(has(refusal(configure(pulls, request("c", ring_b, "/ln/unit/a"), "other")),
                 "not in the namespace")); // (its ring is checked first)
    List l = status(pulls);
    LN_CHECK_EQ(l.ports.size(), 1);
    LN_CHECK_EQ(l.topics.size(), 2);
    if (l.ports.size() != 1 || l.topics.size() != 2)
        return;
    uint16_t port = l.ports[0].port;
    LN_CHECK(port != 0);
    CHECK_STR(l.ports[0].address, "127.0.0.1");
    CHECK_STR(l.topics[0].topic, "a");
    CHECK_STR(l.topics[0].name, "/ln/unit/a");
    CHECK_STR(l.topics[0].ring, ring_a.name());
    LN_CHECK_EQ(l.topics[0].port, port);
    LN_CHECK_EQ(l.topics[1].port, port);
    LN_CHECK(status(pulls, "", "other").topics.empty()); // another instance sees nothing

    // served end to end through the table
    for (uint64_t s = 1; s <= 3; ++s)
        LN_CHECK_EQ(pub.publish(s), LN_OK);
    LN_CHECK(wait_until([&] { return status(pulls, "a").topics[0].latest_seq == 3; }));
    pulltest::Consumer consumer(port);
    consumer.interest("/ln/unit/a/seq=2", 1);
    pulltest::Reply r;
    LN_CHECK(consumer.receive(r));
    CHECK_STR(r.uri, "/ln/unit/a/seq=2");
    LN_CHECK_EQ(r.pkt.data.freshness_ms, 500);
    LN_CHECK(fwdtest::matches(r.content.payload.data, 64, 2));

    // an update in place keeps the history and takes the new freshness and name
    PullTopicRequest q = request("a", ring_a, "/ln/unit/a2");
    q.freshness_ms = 250;
    LN_CHECK(is_ok(configure(pulls, q)));
    l = status(pulls, "a");
    LN_CHECK_EQ(l.topics[0].latest_seq, 3);
    CHECK_STR(l.topics[0].name, "/ln/unit/a2");
    LN_CHECK_EQ(l.topics[0].counters.data, 1);
    consumer.interest("/ln/unit/a2/seq=3", 2);
    LN_CHECK(consumer.receive(r));
    CHECK_STR(r.uri, "/ln/unit/a2/seq=3");
    LN_CHECK_EQ(r.pkt.data.freshness_ms, 250);
    LN_CHECK(fwdtest::matches(r.content.payload.data, 64, 3));
    // the old name is not served any more
    consumer.interest("/ln/unit/a/seq=3", 3);
    LN_CHECK(wait_until([&] { return status(pulls).ports[0].counters.unknown == 1; }));

    // another history size reallocates: the samples go
    q.history = 16;
    LN_CHECK(is_ok(configure(pulls, q)));
    LN_CHECK_EQ(status(pulls, "a").topics[0].latest_seq, 0);
    LN_CHECK_EQ(status(pulls, "a").topics[0].history, 16);

    // a move to another port; b stays where it was
    q.address = "127.0.0.2";
    LN_CHECK(is_ok(configure(pulls, q)));
    l = status(pulls);
    LN_CHECK_EQ(l.ports.size(), 2);
    CHECK_STR(status(pulls, "a").topics[0].address, "127.0.0.2");
    CHECK_STR(status(pulls, "b").topics[0].address, "127.0.0.1");
    LN_CHECK_EQ(status(pulls, "b").topics[0].port, port);

    // removing b closes its port (a's stays); "" removes the rest
    LN_CHECK(is_ok(named(pulls, proto::Msg::pull_remove, "b")));
    l = status(pulls);
    LN_CHECK_EQ(l.ports.size(), 1);
    LN_CHECK_EQ(l.topics.size(), 1);
    lnd::UniqueFd again(::socket(AF_INET, SOCK_DGRAM, 0)); // the port is free again
    sockaddr_in sa{};
    sa.sin_family = AF_INET;
    sa.sin_port = htons(port);
    sa.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    LN_CHECK_EQ(::bind(again.get(), reinterpret_cast<sockaddr *>(&sa), sizeof sa), 0);
    LN_CHECK(is_ok(named(pulls, proto::Msg::pull_remove, "")));
    LN_CHECK(status(pulls).topics.empty());
    LN_CHECK(status(pulls).ports.empty());
    LN_CHECK_EQ(pulls.memory_used(), 0);
}

} // namespace

int main()
{
    LN_TEST_RUN(test_refusals);
    LN_TEST_RUN(test_shared_port_update_move_remove);
    LN_TEST_EXIT();
}
