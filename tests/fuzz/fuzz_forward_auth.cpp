// fuzz_forward_auth.cpp — fuzz target: the authentication of forwarded UDP datagrams
// (forward_udp_guard.cpp with forward_wire.cpp and forward_crypto.cpp), as the receive
// thread runs it.  The input is a security level byte, then datagrams, each a u16le length
// and its bytes.  Besides not crashing: no counter of one salt is ever admitted twice, and
// nothing is admitted unless the datagram was sealed with the stream's key (the seeds are).
#include <cstdint>
#include <cstring>
#include <set>
#include <utility>
#include <vector>

#include "forward_crypto.hpp"
#include "forward_udp_guard.hpp"
#include "forward_wire.hpp"

extern "C" {
#include "fuzz.h"
}

using namespace lnd::fwd;

namespace {

constexpr uint64_t kToken = 0x5eed;

lnd::Key stream_key()
{
    lnd::Key daemon, out;
    std::memset(daemon.bytes, 0x42, lnd::Key::kBytes);
    sec::stream_key(daemon, kToken, 0, out);
    return out;
}

// A datagram sealed as UdpSender does: 100-byte sample, chunks of 40.
std::vector<uint8_t> sealed(sec::Suite suite, uint64_t salt, uint64_t counter, uint32_t index)
{
    const lnd::Key key = stream_key();
    uint8_t raw[8];
    for (int i = 0; i < 8; ++i)
        raw[i] = static_cast<uint8_t>(salt >> (8 * i));
    lnd::Key k;
    sec::sub_key(key, "udp salt", raw, sizeof raw, k);
    sec::Box box(k, suite);
    wire::Fragment f;
    f.token = kToken;
    f.seq = 1;
    f.sample_size = 100;
    f.chunk_size = 40;
    f.count = 3;
    f.index = index;
    f.suite = static_cast<uint8_t>(suite);
    f.salt = salt;
    f.counter = counter;
    const size_t length = wire::fragment_length(100, 40, index);
    std::vector<uint8_t> d(wire::kFragmentHeaderSize + length + sec::tag_bytes(suite));
    wire::encode_fragment_header(d.data(), f);
    uint8_t *payload = d.data() + wire::kFragmentHeaderSize;
    std::memset(payload, static_cast<int>(index), length);
    box.seal(counter, d.data(), wire::kFragmentHeaderSize, payload, length, payload,
             payload + length);
    return d;
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 1)
        return 0;
    static const lnd::Key key = stream_key();
    UdpGuard guard(static_cast<sec::Level>(data[0] % 3), key);
    std::set<std::pair<uint64_t, uint64_t>> admitted; // (salt, counter)
    std::vector<uint8_t> buf;
    for (size_t at = 1; at + 2 <= size;) {
        size_t n = data[at] | data[at + 1] << 8;
        at += 2;
        if (n > size - at)
            n = size - at;
        buf.assign(data + at, data + at + n);
        at += n;
        wire::Fragment f;
        if (!wire::decode_fragment(buf.data(), buf.size(), f) || f.token != kToken)
            continue;
        if (guard.admit(f, buf.data()) != nullptr || f.suite == 0)
            continue;
        if (!admitted.insert({f.salt, f.counter}).second)
            __builtin_trap(); // a replay got through
    }
    return 0;
}

extern "C" void ln_fuzz_seeds(ln_fuzz_emit *emit)
{
    // Level byte, then length-prefixed datagrams: a sample, a replay of its first datagram,
    // a newer salt, an older one.
    for (auto suite : {sec::Suite::poly1305, sec::Suite::chacha20poly1305}) {
        std::vector<uint8_t> in = {static_cast<uint8_t>(suite == sec::Suite::poly1305 ? 1 : 2)};
        auto add = [&in](const std::vector<uint8_t> &d) {
            in.push_back(static_cast<uint8_t>(d.size()));
            in.push_back(static_cast<uint8_t>(d.size() >> 8));
            in.insert(in.end(), d.begin(), d.end());
        };
        add(sealed(suite, 1000, 1, 0));
        add(sealed(suite, 1000, 2, 1));
        add(sealed(suite, 1000, 3, 2));
        add(sealed(suite, 1000, 1, 0));
        add(sealed(suite, 2000, 1, 0));
        add(sealed(suite, 1000, 9, 0));
        emit(suite == sec::Suite::poly1305 ? "authenticate_sample" : "encrypt_sample", in.data(),
             in.size());
    }
    std::vector<uint8_t> none = {0};
    auto d = sealed(sec::Suite::none, 0, 0, 0);
    none.push_back(static_cast<uint8_t>(d.size()));
    none.push_back(0);
    none.insert(none.end(), d.begin(), d.end());
    emit("none_sample", none.data(), none.size());
}
