// fuzz_forward_udp.cpp — fuzz target: the forwarder's UDP receive path (forward_wire.cpp,
// forward_reassembly.cpp) on datagrams split from the input, as UdpReceiver::handle uses it;
// completed samples must be whole and the reassembly budget given back in full.
#include <cassert>
#include <cstdint>
#include <cstring>
#include <map>
#include <set>
#include <string>
#include <utility>

#include "forward_reassembly.hpp"
#include "forward_wire.hpp"

extern "C" {
#include "fuzz.h"
}

using namespace lnd::fwd;

namespace {

uint64_t checksum(const uint8_t *p, uint64_t n)
{
    uint64_t sum = 0;
    for (uint64_t i = 0; i < n; ++i)
        sum = sum * 31 + p[i]; // reads every byte: the sanitizer sees a short buffer
    return sum;
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 3)
        return 0;
    // The stream's message size and the budget: small, so limits are reached.
    uint64_t message_size = (data[0] | data[1] << 8) % 4096;
    size_t max_incomplete = 1 + data[2] % 4;
    data += 3;
    size -= 3;
    ReassemblyBudget budget(8192);
    volatile uint64_t sink = 0;
    {
        Reassembler reassembler(budget, max_incomplete);
        uint64_t newest = 0; // the ring's newest sequence number
        // Fragment indexes handed in, per sample and chunk size (which fixes the count).
        std::map<std::pair<uint64_t, uint16_t>, std::set<uint32_t>> given;
        int64_t now = 1000000000;
        // Datagrams, each either raw (u16 length < 0x8000, then its bytes) or compact
        // (0x8000, then u8 seq, index, chunk - 1, count delta, length), which the wire
        // encoder turns into a header with small numbers and a payload of `length` bytes.
        while (size >= 2) {
            size_t len = data[0] | data[1] << 8;
            data += 2;
            size -= 2;
            std::string datagram;
            if (len & 0x8000) {
                uint8_t c[5] = {};
                std::memcpy(c, data, size < sizeof c ? size : sizeof c);
                data += size < sizeof c ? size : sizeof c;
                size -= size < sizeof c ? size : sizeof c;
                wire::Fragment h;
                h.token = 0xfeed;
                h.seq = c[0];
                h.timestamp_ns = 1000 * c[0];
                h.sample_size = message_size;
                h.index = c[1];
                h.chunk_size = static_cast<uint16_t>(c[2] + 1);
                h.count = static_cast<uint32_t>(wire::fragment_count(message_size, h.chunk_size) +
                                                static_cast<int8_t>(c[3]));
                uint8_t header[wire::kFragmentHeaderSize];
                wire::encode_fragment_header(header, h);
                datagram.assign(reinterpret_cast<const char *>(header), sizeof header);
                datagram.append(c[4], static_cast<char>(c[0]));
            } else {
                if (len > size)
                    len = size;
                // A copy of exactly the datagram's size, as recvmmsg would leave it.
                datagram.assign(reinterpret_cast<const char *>(data), len);
                data += len;
                size -= len;
            }
            now += 1000000;
            wire::Fragment f;
            if (!wire::decode_fragment(reinterpret_cast<const uint8_t *>(datagram.data()),
                                       datagram.size(), f))
                continue;
            if (wire::check_fragment(f, message_size))
                continue;
            assert(f.sample_size == message_size);
            if (f.count == 1) {
                assert(f.length == message_size);
                sink = sink + checksum(f.data, f.length);
                if (f.seq > newest)
                    newest = f.seq;
                if (reassembler.in_progress())
                    reassembler.supersede(f.seq);
                continue;
            }
            given[{f.seq, f.chunk_size}].insert(f.index);
            Reassembler::Outcome o =
                reassembler.add(f, reassembler.active(f.seq) ? 0 : newest, now);
            if (o.kind == Reassembler::Outcome::complete) {
                // complete means every fragment of the sample arrived
                const std::set<uint32_t> &got = given[{f.seq, f.chunk_size}];
                assert(got.size() >= f.count && *got.rbegin() < f.count);
                sink = sink + checksum(o.data, message_size);
                if (f.seq > newest)
                    newest = f.seq;
                reassembler.finish(f.seq);
            }
            if (now % 8000000 == 0)
                reassembler.expire(now, 5000000);
        }
    }
    assert(budget.used() == 0);
    (void)sink;
    return 0;
}

// ---- seeds: samples cut into datagrams by the wire encoder ---------------------------------

namespace {

void datagram(std::string &out, const wire::Fragment &f, const uint8_t *payload)
{
    uint8_t header[wire::kFragmentHeaderSize];
    wire::encode_fragment_header(header, f);
    uint64_t len = wire::fragment_length(f.sample_size, f.chunk_size, f.index);
    size_t total = sizeof header + len;
    out += static_cast<char>(total & 0xff);
    out += static_cast<char>(total >> 8);
    out.append(reinterpret_cast<const char *>(header), sizeof header);
    out.append(reinterpret_cast<const char *>(payload) +
                   static_cast<uint64_t>(f.index) * f.chunk_size,
               len);
}

std::string prefix(uint16_t message_size, uint8_t max_incomplete)
{
    std::string s;
    s += static_cast<char>(message_size & 0xff);
    s += static_cast<char>(message_size >> 8);
    s += static_cast<char>(max_incomplete);
    return s;
}

} // namespace

extern "C" void ln_fuzz_seeds(ln_fuzz_emit *emit)
{
    uint8_t payload[100];
    for (size_t i = 0; i < sizeof payload; ++i)
        payload[i] = static_cast<uint8_t>(i * 7);
    wire::Fragment f;
    f.token = 0xfeed;
    f.timestamp_ns = 1234567890;
    f.sample_size = 100;
    f.chunk_size = 40;
    f.count = static_cast<uint32_t>(wire::fragment_count(100, 40));

    // Two samples: one in order, one out of order with a duplicate.
    std::string s = prefix(100, 1);
    f.seq = 5;
    for (uint32_t i = 0; i < f.count; ++i) {
        f.index = i;
        datagram(s, f, payload);
    }
    f.seq = 6;
    for (uint32_t i : {2u, 0u, 0u, 1u}) {
        f.index = i;
        datagram(s, f, payload);
    }
    emit("two_samples", s.data(), s.size());

    // Interleaved samples, one never completed.
    s = prefix(100, 1);
    for (uint32_t i = 0; i < f.count; ++i) {
        for (uint64_t seq : {9u, 10u, 11u}) {
            f.seq = seq;
            f.index = i;
            if (seq != 10 || i != 1)
                datagram(s, f, payload);
        }
    }
    emit("interleaved", s.data(), s.size());

    // Single-datagram samples.
    s = prefix(24, 0);
    f.sample_size = 24;
    f.chunk_size = 1400;
    f.count = 1;
    f.index = 0;
    for (uint64_t seq : {1u, 3u, 2u}) {
        f.seq = seq;
        datagram(s, f, payload);
    }
    emit("single", s.data(), s.size());

    // Compact records: sample 1 of 100 bytes in chunks of 40, its fragments out of order.
    s = prefix(100, 2);
    for (uint8_t i : {1, 0, 2}) {
        uint8_t length = i == 2 ? 20 : 40;
        const uint8_t record[7] = {0x00, 0x80, 1, i, 39, 0, length};
        s.append(reinterpret_cast<const char *>(record), sizeof record);
    }
    emit("compact", s.data(), s.size());
}
