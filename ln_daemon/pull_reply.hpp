// What the two kinds of pull threads (a port's receive thread, a topic's ring reader) share to
// answer Interests: the consumer's address and PIT token (PullPeer), and PullSender, the
// fixed buffers one thread encodes a signed Data packet into and sends it from, bare or in
// an NDNLPv2 LpPacket carrying the PIT token.  Nothing here allocates after construction.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <sys/socket.h>
#include <vector>

#include <ln/ndn.h>

namespace lnd {

constexpr uint64_t kMaxPullMessage = 8000; // one sample per datagram, no segmentation
constexpr size_t kMaxPitToken = 32;
constexpr size_t kPullErrorBytes = 256;

// Where a reply goes: the Interest's source address and the PIT token it carried (if any).
struct PullPeer {
    sockaddr_storage addr{};
    socklen_t addr_len = 0;
    uint8_t token[kMaxPitToken] = {};
    uint8_t token_size = 0;
};

// A problem text kept in place (no allocation when it is set per packet).
struct ErrorText {
    char text[kPullErrorBytes] = "";
    // Sets it; true if it changed (so the caller logs each new problem once).
    bool set(const char *fmt, ...) noexcept __attribute__((format(printf, 2, 3)));
};

// "1.2.3.4:5" or "[::1]:5" into out[size].
void peer_text(const sockaddr_storage &addr, char *out, size_t size) noexcept;

class PullSender {
public:
    // Buffers for a sample of up to `max_message` bytes under a name of up to `max_name`.
    PullSender(uint64_t max_message, size_t max_name);

    void set_fd(int fd) noexcept { fd_ = fd; }
    // Room for one sample's bytes (max_message), for the caller to copy a sample into.
    uint8_t *payload() noexcept { return payload_.data(); }

    // `base` (a name value) with a SequenceNum component appended, in the sender's name
    // buffer; size 0 if it does not fit.
    ln_ndn_bytes name_with_seq(ln_ndn_bytes base, uint64_t seq) noexcept;
    // Encodes and signs a Data packet (its name may be the one name_with_seq returned);
    // LN_NDN_OK or the codec's error.
    int encode(ln_ndn_bytes name, uint32_t content_type, uint32_t freshness_ms,
               const ln_ndn_pull_content &content, const ln_ndn_signer &signer) noexcept;
    // Sends the last encoded packet to `peer` (in an LpPacket if it has a PIT token), never
    // blocking; 0 or an errno (ENOSPC: the LpPacket does not fit).
    int send(const PullPeer &peer) noexcept;

private:
    int fd_ = -1;
    std::vector<uint8_t> payload_;
    std::vector<uint8_t> name_;
    std::vector<uint8_t> content_;
    std::vector<uint8_t> packet_;
    std::vector<uint8_t> lp_;
    size_t packet_size_ = 0;
};

} // namespace lnd
