// Unit tests of the daemon's ring and forwarding commands without a network: the RING_* and
// STREAM_* decoders against truncated, trailing and out-of-range input, the STREAM_LIST
// layout, instance namespaces, LN_HOST_ID defaulting, and the RingTable on real segments of
// a private instance (removed again at the end).
#include <cmath>
#include <cstdint>
#include <ln/ln.h>
#include <ln_admin.h>
#include <string>
#include <sys/stat.h>
#include <unistd.h>
#include <vector>

#include "daemon_test.hpp"
#include "net_messages.hpp"
#include "rings.hpp"
#include "spec.hpp"

using namespace lnd;

namespace {

// Decodes `payload` with `decode`; also checks that every truncation of it and the payload
// with one byte more are refused.
template <typename T>
bool decodes(const std::string &payload, bool (*decode)(proto::Reader &, T &), T &out)
{
    int accepted = 0;
    for (size_t n = 0; n < payload.size(); ++n) {
        proto::Reader r(payload.data(), n);
        T partial{};
        accepted += decode(r, partial);
    }
    LN_CHECK_EQ(accepted, 0);
    std::string longer = payload + "x";
    proto::Reader extra(longer.data(), longer.size());
    T ignored{};
    LN_CHECK(!decode(extra, ignored));
    proto::Reader r(payload.data(), payload.size());
    return decode(r, out);
}

std::string ring_create_payload(uint8_t adopt, const std::string &name = "/ln.i.1.1")
{
    proto::Writer w;
    w.str(name);
    w.str("/arm/state");
    w.str("robot/joint_state");
    w.u64(0x1122334455667788u);
    w.u64(96);
    w.u32(8);
    w.u8(adopt);
    return w.buffer();
}

void test_decode_rings()
{
    RingCreateRequest create;
    LN_CHECK(decodes(ring_create_payload(1), decode_ring_create, create));
    CHECK_STR(create.name, "/ln.i.1.1");
    CHECK_STR(create.topic, "/arm/state");
    CHECK_STR(create.md_name, "robot/joint_state");
    LN_CHECK(create.layout_hash == 0x1122334455667788u);
    LN_CHECK_EQ(create.message_size, 96);
    LN_CHECK_EQ(create.slots, 8);
    LN_CHECK(create.adopt);
    LN_CHECK(decodes(ring_create_payload(0), decode_ring_create, create));
    LN_CHECK(!create.adopt);
    std::string bad_flag = ring_create_payload(2);
    proto::Reader flag(bad_flag.data(), bad_flag.size());
    LN_CHECK(!decode_ring_create(flag, create));
    std::string long_name = ring_create_payload(0, "/ln.i." + std::string(300, 'x'));
    proto::Reader too_long(long_name.data(), long_name.size());
    LN_CHECK(!decode_ring_create(too_long, create));

    proto::Writer retire;
    retire.str("/ln.i.1.1");
    retire.str("/ln.i.1.2");
    retire.f64(0.5);
    RingRetireRequest rr;
    LN_CHECK(decodes(retire.buffer(), decode_ring_retire, rr));
    CHECK_STR(rr.old_name, "/ln.i.1.1");
    CHECK_STR(rr.successor, "/ln.i.1.2");
    LN_CHECK(rr.timeout == 0.5);

    for (uint8_t reserve : {0, 1, 2}) {
        proto::Writer reader;
        reader.str("/ln.i.1.1");
        reader.u32(3);
        reader.i32(-4);
        reader.u32(2);
        reader.u8(reserve);
        RingReaderRequest req;
        if (reserve > 1) {
            proto::Reader r(reader.buffer().data(), reader.buffer().size());
            LN_CHECK(!decode_ring_reader(r, req));
            continue;
        }
        LN_CHECK(decodes(reader.buffer(), decode_ring_reader, req));
        LN_CHECK_EQ(req.index, 3);
        LN_CHECK_EQ(req.pid, -4);
        LN_CHECK_EQ(req.buffers, 2);
        LN_CHECK_EQ(req.reserve, reserve == 1);
    }

    proto::Writer counts;
    counts.str("/ln.i.1.1");
    counts.u32(1);
    counts.u32(7);
    RingCountsRequest rc;
    LN_CHECK(decodes(counts.buffer(), decode_ring_counts, rc));
    LN_CHECK_EQ(rc.publishers, 1);
    LN_CHECK_EQ(rc.subscribers, 7);

    proto::Writer name;
    name.str("/ln.i.1.1");
    std::string decoded;
    LN_CHECK(decodes(name.buffer(), decode_ring_name, decoded));
    CHECK_STR(decoded, "/ln.i.1.1");
}

std::string stream_send_payload(uint8_t transport)
{
    proto::Writer w;
    w.u64(0xfeedu);
    w.str("/ln.i.1.1");
    w.u64(42);
    w.u64(96);
    w.u8(transport);
    w.str("10.0.0.2");
    w.u16(54377);
    w.u8(2); // security: encrypt
    return w.buffer();
}

void test_decode_streams()
{
    fwd::SendSpec send;
    LN_CHECK(decodes(stream_send_payload(1), decode_stream_send, send));
    LN_CHECK_EQ(send.token, 0xfeed);
    CHECK_STR(send.ring, "/ln.i.1.1");
    LN_CHECK_EQ(send.layout_hash, 42);
    LN_CHECK_EQ(send.message_size, 96);
    LN_CHECK(send.transport == fwd::Transport::tcp);
    CHECK_STR(send.host, "10.0.0.2");
    LN_CHECK_EQ(send.port, 54377);
    LN_CHECK(send.security == fwd::Level::encrypt);
    LN_CHECK(decodes(stream_send_payload(0), decode_stream_send, send));
    LN_CHECK(send.transport == fwd::Transport::udp);
    std::string bad = stream_send_payload(2);
    proto::Reader r(bad.data(), bad.size());
    LN_CHECK(!decode_stream_send(r, send));

    proto::Writer recv;
    recv.u64(7);
    recv.str("/ln.i.1.1");
    recv.u64(42);
    recv.u64(96);
    recv.u8(0);
    recv.u8(0); // security: none
    fwd::RecvSpec spec;
    LN_CHECK(decodes(recv.buffer(), decode_stream_recv, spec));
    LN_CHECK_EQ(spec.token, 7);
    CHECK_STR(spec.ring, "/ln.i.1.1");
    LN_CHECK(spec.transport == fwd::Transport::udp);
    LN_CHECK(spec.security == fwd::Level::none);
    std::string no_level = recv.buffer();
    no_level.back() = 3; // no such security level: refused, never taken for a default
    proto::Reader nl(no_level.data(), no_level.size());
    LN_CHECK(!decode_stream_recv(nl, spec));
    std::string old_manager = recv.buffer();
    old_manager.pop_back(); // a STREAM_RECV of protocol version 1 has no level
    proto::Reader om(old_manager.data(), old_manager.size());
    LN_CHECK(!decode_stream_recv(om, spec));

    proto::Writer token;
    token.u64(99);
    uint64_t t = 0;
    LN_CHECK(decodes(token.buffer(), decode_stream_token, t));
    LN_CHECK_EQ(t, 99);
}

void test_encode_stream_list()
{
    fwd::StreamStats s;
    s.token = 5;
    s.sending = true;
    s.transport = fwd::Transport::tcp;
    s.ring = "/ln.i.1.1";
    s.peer = "10.0.0.2:54377";
    s.samples = 10;
    s.bytes = 960;
    s.drops = 1;
    s.stale = 2;
    s.invalid = 3;
    s.rejected = 4;
    s.connected = false;
    s.last_error = std::string(1000, 'e'); // cut to kMaxStatText
    fwd::Totals totals;
    totals.unknown_stream = 11;
    totals.malformed = 12;
    proto::Writer w;
    encode_stream_list(w, totals, {s});
    const std::string &b = w.buffer();
    proto::Reader r(b.data(), b.size());
    LN_CHECK_EQ(r.u64(), 11);
    LN_CHECK_EQ(r.u64(), 12);
    LN_CHECK_EQ(r.u32(), 1);
    LN_CHECK_EQ(r.u64(), 5);
    LN_CHECK_EQ(r.u8(), 1);
    LN_CHECK_EQ(r.u8(), 1);
    CHECK_STR(r.str(), "/ln.i.1.1");
    CHECK_STR(r.str(), "10.0.0.2:54377");
    for (uint64_t want : {10, 960, 1, 2, 3, 4})
        LN_CHECK_EQ(r.u64(), want);
    LN_CHECK_EQ(r.u8(), 0);
    LN_CHECK_EQ(r.str().size(), kMaxStatText);
    LN_CHECK(r.done());
}

void test_names()
{
    CHECK_STR(net_msg_name(static_cast<uint8_t>(proto::Msg::ring_create)), "RING_CREATE");
    CHECK_STR(net_msg_name(static_cast<uint8_t>(proto::Msg::stream_stats)), "STREAM_STATS");
    LN_CHECK(net_msg_name(static_cast<uint8_t>(proto::Msg::spawn)) == nullptr);
    LN_CHECK(net_msg_name(0x4c) == nullptr);

    CHECK_STR(sanitize_instance("lab-1_a"), "lab-1_a");
    CHECK_STR(sanitize_instance("a.b/c d"), "a_b_c_d");
    CHECK_STR(sanitize_instance("k\xc3\xa4se"), "k_se"); // one '_' per character
    CHECK_STR(sanitize_instance("\xe2\x82\xac!"), "__"); // as segments.sanitize_instance
    CHECK_STR(ring_prefix("a.b"), "/ln.a_b.");

    std::string error;
    LN_CHECK(passed(ring_in_namespace("lab", "/ln.lab.3.1"), error));
    LN_CHECK(passed(ring_in_namespace("a.b", "/ln.a_b.3.1"), error));
    for (const char *bad : {"/ln.lab.", "/ln.lab", "/ln.laboratory.3.1", "/ln.other.3.1",
                            "ln.lab.3.1", "/ln.lab.3/1", "/ln.lab.3.1/"}) {
        error.clear();
        LN_CHECK(!passed(ring_in_namespace("lab", bad), error));
        LN_CHECK(error.find("not in the namespace of instance lab") != std::string::npos);
    }
}

void test_env_default()
{
    std::vector<std::string> env{"PATH=/bin", "LN_HOST_IDX=1"};
    env_default(env, "LN_HOST_ID", "here");
    LN_CHECK_EQ(env.size(), 3);
    CHECK_STR(env.back(), "LN_HOST_ID=here");
    env_default(env, "LN_HOST_ID", "elsewhere"); // present: left alone
    LN_CHECK_EQ(env.size(), 3);
    std::vector<std::string> own{"LN_HOST_ID="};
    env_default(own, "LN_HOST_ID", "here");
    LN_CHECK_EQ(own.size(), 1);
}

uint64_t shm_size(const std::string &name)
{
    struct stat st;
    std::string path = "/dev/shm" + name;
    return ::stat(path.c_str(), &st) == 0 ? static_cast<uint64_t>(st.st_size) : 0;
}

void test_ring_table()
{
    // Real segments under an instance of this process alone.
    std::string instance = "daemon-unit." + std::to_string(::getpid());
    std::string prefix = ring_prefix(instance);
    RingCreateRequest req;
    req.name = prefix + "1.1";
    req.topic = "/t";
    req.md_name = "lntest/pattern";
    req.layout_hash = 7;
    req.message_size = 64;
    req.slots = 4;
    std::string error;
    uint64_t purged = 0;
    {
        RingTable table;
        LN_CHECK(passed(table.create(instance, req), error));
        LN_CHECK_EQ(shm_size(req.name), ln_ring_segment_size(64, 4));
        LN_CHECK(!passed(table.create(instance, req), error)); // exists, no adopt
        CHECK_STR(error, "ring " + req.name + " exists already");
        req.adopt = true;
        LN_CHECK(passed(table.create(instance, req), error)); // held: fine
        LN_CHECK_EQ(table.size(), 1);
        // Unlinked by someone else: the stale handle gives way to a new segment.
        LN_CHECK_EQ(ln_ring_admin_unlink(req.name.c_str()), LN_OK);
        req.adopt = false;
        LN_CHECK(passed(table.create(instance, req), error));
        LN_CHECK_EQ(shm_size(req.name), ln_ring_segment_size(64, 4));
        LN_CHECK_EQ(table.size(), 1);
        req.adopt = true;

        RingCountsRequest counts{req.name, 1, 2};
        LN_CHECK(passed(table.counts(instance, counts), error));
        LN_CHECK(!passed(table.counts("other", counts), error));
        LN_CHECK(error.find("not in the namespace of instance other") != std::string::npos);
        RingReaderRequest reader{req.name, 0, static_cast<int32_t>(::getpid()), 2, true};
        LN_CHECK(passed(table.reader(instance, reader), error));
        reader.buffers = 4; // as many as the ring has slots: libln refuses
        LN_CHECK(!passed(table.reader(instance, reader), error));
        LN_CHECK(error.find("reserving reader slot 0 of " + req.name + ": EINVAL: ") == 0);
        uint64_t seq = 99;
        LN_CHECK(passed(table.write_seq(instance, req.name, seq), error));
        LN_CHECK_EQ(seq, 0);
        LN_CHECK(!passed(table.write_seq(instance, prefix + "9.9", seq), error));
        LN_CHECK(error.find("holds no ring") != std::string::npos);

        RingCreateRequest next = req;
        next.name = prefix + "1.2";
        next.slots = 8;
        next.adopt = false;
        LN_CHECK(passed(table.create(instance, next), error));
        RingRetireRequest retire{req.name, next.name, NAN};
        LN_CHECK(!passed(table.retire(instance, retire), error));
        retire.timeout = 1.0;
        LN_CHECK(passed(table.retire(instance, retire), error));
        LN_CHECK(passed(table.remove(instance, req.name), error));
        LN_CHECK_EQ(shm_size(req.name), 0);
        LN_CHECK(passed(table.remove(instance, req.name), error)); // gone already is fine
        LN_CHECK_EQ(table.size(), 1);
    } // the table closes its handles but leaves the segments
    LN_CHECK_EQ(shm_size(prefix + "1.2"), ln_ring_segment_size(64, 8));
    {
        RingTable table; // as after a daemon restart
        RingCreateRequest again = req;
        again.name = prefix + "1.2";
        again.slots = 8;
        again.adopt = false;
        LN_CHECK(!passed(table.create(instance, again), error));
        LN_CHECK(error.find("creating segment " + again.name) == 0);
        again.adopt = true;
        again.slots = 16; // not the geometry of the segment
        LN_CHECK(!passed(table.create(instance, again), error));
        LN_CHECK(error.find("exists with") != std::string::npos);
        again.slots = 8;
        again.layout_hash = 8; // another layout
        LN_CHECK(!passed(table.create(instance, again), error));
        LN_CHECK(error.find("adopting segment " + again.name + ": ELAYOUT: ") == 0);
        again.layout_hash = 7;
        LN_CHECK(passed(table.create(instance, again), error));
        LN_CHECK_EQ(table.size(), 1);
        LN_CHECK(passed(table.purge(instance, purged), error));
        LN_CHECK_EQ(purged, 1);
        LN_CHECK_EQ(table.size(), 0);
    }
    LN_CHECK_EQ(shm_size(prefix + "1.2"), 0);
    ln_ring_admin_purge_instance(sanitize_instance(instance).c_str()); // after a failed check
}

} // namespace

int main()
{
    LN_TEST_RUN(test_decode_rings);
    LN_TEST_RUN(test_decode_streams);
    LN_TEST_RUN(test_encode_stream_list);
    LN_TEST_RUN(test_names);
    LN_TEST_RUN(test_env_default);
    LN_TEST_RUN(test_ring_table);
    LN_TEST_EXIT();
}
