// Encoding and sending pull replies (pull_reply.hpp).  A reply's buffers are sized when the
// sender is made: the payload, the header TLVs, the name, the signature and the LpPacket
// around it all fit, so encoding never runs out of room for a sample the topic accepted.
#include "pull_reply.hpp"

#include <arpa/inet.h>
#include <cerrno>
#include <cstdarg>
#include <cstring>
#include <netinet/in.h>

namespace lnd {

namespace {

// Bytes a Data packet needs besides its name value and payload: the Data, Name, MetaInfo,
// Content and payload TLV headers, the three header TLVs, SignatureInfo (with a KeyLocator
// we never write) and the 32-byte SignatureValue, all generously rounded up.
constexpr size_t kDataOverhead = 256;
constexpr size_t kLpOverhead = 16 + kMaxPitToken;

} // namespace

bool ErrorText::set(const char *fmt, ...) noexcept
{
    char fresh[kPullErrorBytes];
    va_list ap;
    va_start(ap, fmt);
    std::vsnprintf(fresh, sizeof fresh, fmt, ap);
    va_end(ap);
    if (std::strcmp(fresh, text) == 0)
        return false;
    std::memcpy(text, fresh, sizeof text);
    return true;
}

void peer_text(const sockaddr_storage &addr, char *out, size_t size) noexcept
{
    char host[INET6_ADDRSTRLEN] = "?";
    unsigned port = 0;
    if (addr.ss_family == AF_INET) {
        const auto *in = reinterpret_cast<const sockaddr_in *>(&addr);
        ::inet_ntop(AF_INET, &in->sin_addr, host, sizeof host);
        port = ntohs(in->sin_port);
    } else if (addr.ss_family == AF_INET6) {
        const auto *in6 = reinterpret_cast<const sockaddr_in6 *>(&addr);
        ::inet_ntop(AF_INET6, &in6->sin6_addr, host, sizeof host);
        port = ntohs(in6->sin6_port);
        std::snprintf(out, size, "[%s]:%u", host, port);
        return;
    }
    std::snprintf(out, size, "%s:%u", host, port);
}

PullSender::PullSender(uint64_t max_message, size_t max_name)
    : payload_(max_message), name_(max_name + 16), content_(max_message + 64),
      packet_(max_message + max_name + 16 + kDataOverhead),
      lp_(max_message + max_name + 16 + kDataOverhead + kLpOverhead)
{}

ln_ndn_bytes PullSender::name_with_seq(ln_ndn_bytes base, uint64_t seq) noexcept
{
    if (base.size > name_.size())
        return {nullptr, 0};
    std::memcpy(name_.data(), base.data, base.size);
    int n = ln_ndn_name_append_seq(name_.data(), name_.size(), base.size, seq);
    if (n < 0)
        return {nullptr, 0};
    return {name_.data(), static_cast<size_t>(n)};
}

int PullSender::encode(ln_ndn_bytes name, uint32_t content_type, uint32_t freshness_ms,
                       const ln_ndn_pull_content &content, const ln_ndn_signer &signer) noexcept
{
    packet_size_ = 0;
    int n = ln_ndn_encode_pull_content(content_.data(), content_.size(), &content);
    if (n < 0)
        return n;
    ln_ndn_data d{};
    d.name = name;
    d.content_type = content_type;
    d.freshness_ms = freshness_ms;
    d.content = {content_.data(), static_cast<size_t>(n)};
    n = ln_ndn_encode_data(packet_.data(), packet_.size(), &d, &signer);
    if (n < 0)
        return n;
    packet_size_ = static_cast<size_t>(n);
    return LN_NDN_OK;
}

int PullSender::send(const PullPeer &peer) noexcept
{
    const uint8_t *out = packet_.data();
    size_t size = packet_size_;
    if (peer.token_size > 0) {
        int n = ln_ndn_encode_lp(lp_.data(), lp_.size(), {peer.token, peer.token_size},
                                 packet_.data(), packet_size_);
        if (n < 0)
            return ENOSPC;
        out = lp_.data();
        size = static_cast<size_t>(n);
    }
    ssize_t sent = ::sendto(fd_, out, size, MSG_DONTWAIT | MSG_NOSIGNAL,
                            reinterpret_cast<const sockaddr *>(&peer.addr), peer.addr_len);
    return sent < 0 ? errno : 0;
}

} // namespace lnd
