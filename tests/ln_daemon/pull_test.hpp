// pull_test.hpp — what the pull topic tests share: a consumer on a UDP socket of its own that
// sends Interests (bare or in an LpPacket with a PIT token) to a pull port on 127.0.0.1 and
// decodes what comes back, and a way to wait for a topic's counters (the deadline only stops
// a hung test; nothing is timed).
#ifndef LN_PULL_TEST_HPP
#define LN_PULL_TEST_HPP

#include <arpa/inet.h>
#include <cstdint>
#include <cstring>
#include <netinet/in.h>
#include <poll.h>
#include <string>
#include <sys/socket.h>
#include <unistd.h>
#include <vector>

#include <ln/ndn.h>

#include "daemon_test.hpp"
#include "fd.hpp"

namespace pulltest {

// A name value from a URI (empty if the URI is bad).
inline std::vector<uint8_t> name_of(const std::string &uri)
{
    std::vector<uint8_t> out(uri.size() * 2 + 64);
    int n = ln_ndn_name_from_uri(out.data(), out.size(), uri.c_str());
    out.resize(n > 0 ? static_cast<size_t>(n) : 0);
    return out;
}

inline std::string uri_of(ln_ndn_bytes name)
{
    char buf[1024];
    return ln_ndn_name_to_uri(buf, sizeof buf, name) >= 0 ? buf : "?";
}

// One reply, decoded (the views point into buf, so a Reply is not copied).
struct Reply {
    std::vector<uint8_t> buf;
    ln_ndn_packet pkt{};
    ln_ndn_pull_content content{};
    std::string uri;
    bool nack() const { return pkt.data.content_type == LN_NDN_CONTENT_NACK; }
};

class Consumer {
public:
    explicit Consumer(uint16_t port) : fd_(::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0))
    {
        to_.sin_family = AF_INET;
        to_.sin_port = htons(port);
        to_.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
        sockaddr_in any{};
        any.sin_family = AF_INET;
        any.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
        LN_CHECK_EQ(::bind(fd_.get(), reinterpret_cast<sockaddr *>(&any), sizeof any), 0);
    }

    void raw(const void *data, size_t size)
    {
        ssize_t n =
            ::sendto(fd_.get(), data, size, 0, reinterpret_cast<sockaddr *>(&to_), sizeof to_);
        LN_CHECK_EQ(n, static_cast<ssize_t>(size));
    }

    // Sends an Interest for `uri` ("/p/t/seq=3", "/p/t/sync"); a sync gets CanBePrefix and
    // MustBeFresh.  With a token, it goes in an LpPacket carrying it.
    void interest(const std::string &uri, uint32_t nonce, uint32_t lifetime_ms = 4000,
                  const std::string &token = "")
    {
        std::vector<uint8_t> name = name_of(uri);
        LN_CHECK(!name.empty());
        ln_ndn_interest in{};
        in.name = {name.data(), name.size()};
        in.nonce = nonce;
        in.has_nonce = 1;
        in.lifetime_ms = lifetime_ms;
        bool sync = uri.size() >= 5 && uri.compare(uri.size() - 5, 5, "/sync") == 0;
        in.can_be_prefix = sync;
        in.must_be_fresh = sync;
        uint8_t pkt[2048], lp[2200];
        int n = ln_ndn_encode_interest(pkt, sizeof pkt, &in);
        LN_CHECK(n > 0);
        if (n <= 0)
            return;
        if (token.empty())
            return raw(pkt, static_cast<size_t>(n));
        int m = ln_ndn_encode_lp(lp, sizeof lp,
                                 {reinterpret_cast<const uint8_t *>(token.data()), token.size()},
                                 pkt, static_cast<size_t>(n));
        LN_CHECK(m > 0);
        if (m > 0)
            raw(lp, static_cast<size_t>(m));
    }

    // The next reply within `timeout_ms`; false if none came (or it did not decode).
    bool receive(Reply &r, int timeout_ms = 10000)
    {
        pollfd p{fd_.get(), POLLIN, 0};
        if (::poll(&p, 1, timeout_ms) != 1)
            return false;
        r.buf.assign(16384, 0);
        ssize_t n = ::recv(fd_.get(), r.buf.data(), r.buf.size(), 0);
        if (n <= 0)
            return false;
        r.buf.resize(static_cast<size_t>(n));
        if (ln_ndn_decode(r.buf.data(), r.buf.size(), &r.pkt) != LN_NDN_OK ||
            r.pkt.type != LN_NDN_T_DATA)
            return false;
        r.uri = uri_of(r.pkt.data.name);
        return ln_ndn_decode_pull_content(r.pkt.data.content, &r.content) == LN_NDN_OK;
    }

    // True if a datagram is waiting right now.
    bool pending()
    {
        pollfd p{fd_.get(), POLLIN, 0};
        return ::poll(&p, 1, 0) == 1;
    }

private:
    lnd::UniqueFd fd_;
    sockaddr_in to_{};
};

} // namespace pulltest

#endif // LN_PULL_TEST_HPP
