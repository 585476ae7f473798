// Unit tests of the forwarder's pure pieces: the wire format byte for byte (it is the
// contract with other daemons' versions, docs/network.md), the fragment geometry checks,
// and the reassembler's rules (duplicates, mismatches, eviction, the memory budget, expiry).
#include <cstring>
#include <vector>

#include "daemon_test.hpp"
#include "forward_reassembly.hpp"
#include "forward_wire.hpp"

using namespace lnd::fwd;

namespace {

void test_fragment_header_layout()
{
    wire::Fragment f;
    f.token = 0x0102030405060708ull;
    f.seq = 0x1112131415161718ull;
    f.timestamp_ns = -2;
    f.sample_size = 0x2122232425262728ull;
    f.index = 0x31323334;
    f.count = 0x41424344;
    f.chunk_size = 0x5152;
    f.salt = 0x6162636465666768ull;
    f.suite = 1;
    f.counter = 0x71727374757677ull;
    uint8_t h[wire::kFragmentHeaderSize];
    wire::encode_fragment_header(h, f);
    const uint8_t want[64] = {
        'L',  'N',  'F',  '1',  3,    0,    0x52, 0x51, // magic, version, kind, chunk
        0x08, 0x07, 0x06, 0x05, 0x04, 0x03, 0x02, 0x01, // token
        0x18, 0x17, 0x16, 0x15, 0x14, 0x13, 0x12, 0x11, // seq
        0xfe, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, // timestamp
        0x28, 0x27, 0x26, 0x25, 0x24, 0x23, 0x22, 0x21, // sample size
        0x34, 0x33, 0x32, 0x31, 0x44, 0x43, 0x42, 0x41, // index, count
        0x68, 0x67, 0x66, 0x65, 0x64, 0x63, 0x62, 0x61, // salt
        0x77, 0x76, 0x75, 0x74, 0x73, 0x72, 0x71, 0x01, // counter, suite
    };
    LN_CHECK(std::memcmp(h, want, sizeof want) == 0);
    wire::set_fragment_index(h, 7);
    wire::Fragment g;
    std::vector<uint8_t> d(h, h + sizeof h);
    d.push_back(0xaa);
    d.resize(d.size() + wire::kFragmentTagSize, 0xcc); // the tag
    LN_CHECK(wire::decode_fragment(d.data(), d.size(), g));
    LN_CHECK_EQ(g.salt, f.salt);
    LN_CHECK_EQ(g.counter, f.counter);
    LN_CHECK_EQ(g.suite, 1);
    LN_CHECK(g.tag == d.data() + 65);
    // A tagged datagram too short for its tag is not one of ours.
    LN_CHECK(!wire::decode_fragment(d.data(), 64 + wire::kFragmentTagSize - 1, g));
    d.resize(65);
    d[63] = 0; // suite none: no tag
    LN_CHECK(wire::decode_fragment(d.data(), d.size(), g));
    LN_CHECK(g.tag == nullptr);
    LN_CHECK_EQ(g.token, f.token);
    LN_CHECK_EQ(g.seq, f.seq);
    LN_CHECK_EQ(g.timestamp_ns, -2);
    LN_CHECK(g.sample_size == f.sample_size);
    LN_CHECK_EQ(g.index, 7);
    LN_CHECK_EQ(g.count, f.count);
    LN_CHECK_EQ(g.chunk_size, 0x5152);
    LN_CHECK_EQ(g.length, 1);
    LN_CHECK(g.data == d.data() + 64);
    LN_CHECK(!wire::decode_fragment(d.data(), 63, g));
    d[4] = 2; // the version before security
    LN_CHECK(!wire::decode_fragment(d.data(), d.size(), g));
}

void test_tcp_messages_layout()
{
    uint8_t hello[wire::kHelloSize];
    wire::Hello hi;
    hi.token = 0x0102030405060708ull;
    hi.message_size = 64;
    hi.layout_hash = 0xa1a2a3a4a5a6a7a8ull;
    hi.suite = 2;
    std::memset(hi.nonce, 0xbb, sizeof hi.nonce);
    std::memset(hi.tag, 0xcc, sizeof hi.tag);
    wire::encode_hello(hello, hi);
    const uint8_t want[40] = {'L',  'N',  'F',  '1',  3, 1, 0, 0, 8, 7, 6,    5,    4,    3,
                              2,    1,    64,   0,    0, 0, 0, 0, 0, 0, 0xa8, 0xa7, 0xa6, 0xa5,
                              0xa4, 0xa3, 0xa2, 0xa1, 2, 0, 0, 0, 0, 0, 0,    0};
    LN_CHECK(std::memcmp(hello, want, sizeof want) == 0);
    LN_CHECK(hello[40] == 0xbb && hello[55] == 0xbb && hello[56] == 0xcc && hello[71] == 0xcc);
    wire::Hello h;
    LN_CHECK(wire::decode_hello(hello, h));
    LN_CHECK_EQ(h.message_size, 64);
    LN_CHECK_EQ(h.suite, 2);
    LN_CHECK(std::memcmp(h.nonce, hi.nonce, sizeof h.nonce) == 0);
    hello[33] = 1; // the suite's reserved bytes
    LN_CHECK(!wire::decode_hello(hello, h));
    hello[33] = 0;
    hello[5] = 0; // a fragment's kind
    LN_CHECK(!wire::decode_hello(hello, h));

    uint8_t reply[wire::kReplySize];
    wire::encode_reply(reply, {wire::Kind::reject, wire::Reject::layout, 9});
    const uint8_t want_reply[16] = {'L', 'N', 'F', '1', 3, 3, 2, 0, 9, 0, 0, 0, 0, 0, 0, 0};
    LN_CHECK(std::memcmp(reply, want_reply, sizeof want_reply) == 0);
    wire::Reply r;
    LN_CHECK(wire::decode_reply(reply, r));
    LN_CHECK(r.kind == wire::Kind::reject);
    LN_CHECK(r.reason == wire::Reject::layout);
    reply[6] = 1; // an accept carries no reason
    reply[5] = 2;
    LN_CHECK(!wire::decode_reply(reply, r));

    uint8_t frame[wire::kFrameHeaderSize];
    wire::encode_frame_header(frame, {5, -1, 300});
    const uint8_t want_frame[24] = {5,    0,    0,    0,    0,    0, 0, 0, 0xff, 0xff, 0xff, 0xff,
                                    0xff, 0xff, 0xff, 0xff, 0x2c, 1, 0, 0, 0,    0,    0,    0};
    LN_CHECK(std::memcmp(frame, want_frame, sizeof want_frame) == 0);
    wire::FrameHeader fh = wire::decode_frame_header(frame);
    LN_CHECK_EQ(fh.seq, 5);
    LN_CHECK_EQ(fh.timestamp_ns, -1);
    LN_CHECK_EQ(fh.size, 300);

    uint8_t tail[wire::kFrameTrailerSize];
    wire::encode_frame_trailer(tail, true);
    const uint8_t want_intact[8] = {'L', 'N', 'F', 'E', 0, 0, 0, 0};
    LN_CHECK(std::memcmp(tail, want_intact, sizeof want_intact) == 0);
    LN_CHECK(wire::decode_frame_trailer(tail) == wire::Trailer::intact);
    wire::encode_frame_trailer(tail, false);
    const uint8_t want_torn[8] = {'L', 'N', 'F', 'E', 1, 0, 0, 0};
    LN_CHECK(std::memcmp(tail, want_torn, sizeof want_torn) == 0);
    LN_CHECK(wire::decode_frame_trailer(tail) == wire::Trailer::torn);
    tail[4] = 2; // no such state
    LN_CHECK(wire::decode_frame_trailer(tail) == wire::Trailer::invalid);
    tail[4] = 0;
    tail[3] = 'X'; // not a trailer: payload bytes where the trailer should be
    LN_CHECK(wire::decode_frame_trailer(tail) == wire::Trailer::invalid);
}

wire::Fragment frag(uint64_t seq, uint64_t size, uint16_t chunk, uint32_t index,
                    const uint8_t *sample)
{
    wire::Fragment f;
    f.token = 1;
    f.seq = seq;
    f.timestamp_ns = static_cast<int64_t>(seq) * 10;
    f.sample_size = size;
    f.chunk_size = chunk;
    f.count = static_cast<uint32_t>(wire::fragment_count(size, chunk));
    f.index = index;
    f.data = sample + static_cast<uint64_t>(index) * chunk;
    f.length = wire::fragment_length(size, chunk, index);
    return f;
}

void test_fragment_checks()
{
    LN_CHECK_EQ(wire::fragment_count(3000, 1000), 3);
    LN_CHECK_EQ(wire::fragment_count(3001, 1000), 4);
    LN_CHECK_EQ(wire::fragment_count(1, 1000), 1);
    LN_CHECK_EQ(wire::fragment_length(3001, 1000, 3), 1);
    LN_CHECK_EQ(wire::fragment_length(3001, 1000, 2), 1000);
    std::vector<uint8_t> s(3001);
    LN_CHECK(wire::check_fragment(frag(1, 3001, 1000, 3, s.data()), 3001) == nullptr);
    LN_CHECK(wire::check_fragment(frag(1, 3001, 1000, 3, s.data()), 3000) != nullptr);
    auto f = frag(1, 3001, 1000, 0, s.data());
    f.length = 999;
    LN_CHECK(wire::check_fragment(f, 3001) != nullptr);
    f = frag(1, 3001, 1000, 0, s.data());
    f.index = 4;
    LN_CHECK(wire::check_fragment(f, 3001) != nullptr);
    f = frag(1, 3001, 1000, 0, s.data());
    f.count = 5;
    LN_CHECK(wire::check_fragment(f, 3001) != nullptr);
    f = frag(1, 3001, 1000, 0, s.data());
    f.chunk_size = 0;
    LN_CHECK(wire::check_fragment(f, 3001) != nullptr);
    f = frag(0, 3001, 1000, 0, s.data());
    LN_CHECK(wire::check_fragment(f, 3001) != nullptr);
}

void test_reassembly_rules()
{
    std::vector<uint8_t> a(2500), b(2500);
    for (size_t i = 0; i < a.size(); ++i) {
        a[i] = static_cast<uint8_t>(i * 7);
        b[i] = static_cast<uint8_t>(i * 13 + 1);
    }
    ReassemblyBudget budget(1 << 20);
    {
        Reassembler r(budget, 2);
        using O = Reassembler::Outcome;
        LN_CHECK(r.add(frag(5, 2500, 1000, 2, a.data()), 0, 0).kind == O::pending);
        LN_CHECK(r.add(frag(5, 2500, 1000, 2, a.data()), 0, 0).kind == O::ignored);
        auto bad = frag(5, 2500, 1000, 1, a.data());
        bad.timestamp_ns = 1;
        LN_CHECK(r.add(bad, 0, 0).kind == O::mismatch);
        LN_CHECK(r.add(frag(5, 2500, 1000, 0, a.data()), 0, 0).kind == O::pending);
        O o = r.add(frag(5, 2500, 1000, 1, a.data()), 0, 0);
        LN_CHECK(o.kind == O::complete);
        LN_CHECK(o.data && std::memcmp(o.data, a.data(), a.size()) == 0);
        LN_CHECK_EQ(r.finish(5), 0);
        LN_CHECK_EQ(budget.used(), 0);
        LN_CHECK(r.add(frag(5, 2500, 1000, 1, a.data()), 0, 0).kind == O::ignored); // late
        LN_CHECK(r.add(frag(6, 2500, 1000, 0, b.data()), 6, 0).kind == O::stale);

        // Two in progress (the limit): a newer one pushes out the oldest, an older one is
        // not started.
        LN_CHECK(r.add(frag(10, 2500, 1000, 0, a.data()), 5, 0).kind == O::pending);
        LN_CHECK(r.add(frag(11, 2500, 1000, 0, a.data()), 5, 0).kind == O::pending);
        o = r.add(frag(12, 2500, 1000, 0, a.data()), 5, 0);
        LN_CHECK(o.kind == O::pending);
        LN_CHECK_EQ(o.given_up, 1);
        LN_CHECK(!r.active(10));
        o = r.add(frag(9, 2500, 1000, 0, a.data()), 5, 0);
        LN_CHECK(o.kind == O::too_old);
        LN_CHECK_EQ(o.given_up, 1);
        LN_CHECK(r.add(frag(10, 2500, 1000, 1, a.data()), 5, 0).kind == O::ignored);
        LN_CHECK_EQ(r.supersede(13), 2);
        LN_CHECK_EQ(r.in_progress(), 0);

        // Expiry after a quiet spell.
        LN_CHECK(r.add(frag(20, 2500, 1000, 0, a.data()), 5, 100).kind == O::pending);
        LN_CHECK(r.add(frag(21, 2500, 1000, 0, a.data()), 5, 200).kind == O::pending);
        LN_CHECK_EQ(r.expire(250, 100), 1);
        LN_CHECK(r.active(21));
        LN_CHECK(budget.used() > 0);
    }
    LN_CHECK_EQ(budget.used(), 0); // the destructor gives everything back

    // The budget: two samples of one stream fit, a third pushes out the oldest; a sample
    // that another stream's memory leaves no room for is not started.
    ReassemblyBudget small(2 * 2600);
    Reassembler r1(small, 8), r2(small, 8);
    using O = Reassembler::Outcome;
    LN_CHECK(r1.add(frag(1, 2500, 1000, 0, a.data()), 0, 0).kind == O::pending);
    LN_CHECK(r1.add(frag(2, 2500, 1000, 0, a.data()), 0, 0).kind == O::pending);
    O o = r1.add(frag(3, 2500, 1000, 0, a.data()), 0, 0);
    LN_CHECK(o.kind == O::pending);
    LN_CHECK_EQ(o.given_up, 1);
    LN_CHECK(small.peak() <= 2 * 2600);
    o = r2.add(frag(7, 2500, 1000, 0, b.data()), 0, 0);
    LN_CHECK(o.kind == O::no_memory);
    LN_CHECK_EQ(o.given_up, 1);
    LN_CHECK_EQ(r1.supersede(100), 2);
    LN_CHECK(r2.add(frag(8, 2500, 1000, 0, b.data()), 0, 0).kind == O::pending);
    ReassemblyBudget tiny(100);
    Reassembler r3(tiny, 8);
    LN_CHECK(r3.add(frag(1, 2500, 1000, 0, a.data()), 0, 0).kind == O::no_memory);
}

} // namespace

int main()
{
    LN_TEST_RUN(test_fragment_header_layout);
    LN_TEST_RUN(test_tcp_messages_layout);
    LN_TEST_RUN(test_fragment_checks);
    LN_TEST_RUN(test_reassembly_rules);
    LN_TEST_EXIT();
}
