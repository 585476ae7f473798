// The receive side's check of a UDP datagram's protection (docs/network.md, "Wire format"):
// the suite fits the stream's level, the tag is authentic under the key of the sender's salt,
// the counter is new to the replay window, and a newer salt replaces the current one only
// once one of its datagrams was authentic.  No sockets: forward_udp_recv.cpp asks it for
// every datagram, the fuzz target tests/fuzz/fuzz_forward_auth.cpp for arbitrary bytes.
#pragma once

#include <cstdint>
#include <memory>

#include "forward_crypto.hpp"
#include "forward_wire.hpp"

namespace lnd::fwd {

class UdpGuard {
public:
    // `stream_key` is sec::stream_key of the stream (transport udp).
    UdpGuard(sec::Level level, const Key &stream_key) : level_(level), key_(stream_key) {}

    // nullptr once `f` (decoded from `datagram`, the receive buffer) is authentic: then an
    // encrypted payload is plain text in place and its counter is recorded; else why not.
    const char *admit(wire::Fragment &f, uint8_t *datagram) noexcept;
    uint64_t salt() const noexcept { return salt_; }

private:
    const sec::Level level_;
    const Key key_;
    uint64_t salt_ = 0;             // the sender incarnation whose datagrams are taken
    std::unique_ptr<sec::Box> box_; // its key, nullptr until one datagram was authentic
    sec::ReplayWindow window_;      // its counters seen
};

} // namespace lnd::fwd
