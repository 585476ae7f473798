// The daemon's listening socket and data port (bind.hpp).
#include "bind.hpp"

#include <cerrno>
#include <cstring>
#include <netdb.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <system_error>

#include "log.hpp"

namespace lnd {

namespace {

Outcome cannot(std::string text) { return outcome::error(proto::Err::os_error, std::move(text)); }

} // namespace

Outcome listen_on(const std::string &bind, unsigned port, UniqueFd &out, unsigned &bound)
{
    addrinfo hints = {};
    hints.ai_family = AF_UNSPEC;
    hints.ai_socktype = SOCK_STREAM;
    hints.ai_flags = AI_PASSIVE | AI_NUMERICSERV;
    addrinfo *res = nullptr;
    std::string service = std::to_string(port);
    int rc = ::getaddrinfo(bind.c_str(), service.c_str(), &hints, &res);
    if (rc != 0)
        return cannot("cannot resolve bind address '" + bind + "': " + ::gai_strerror(rc));
    UniqueFd fd(::socket(res->ai_family, SOCK_STREAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0));
    int one = 1;
    if (!fd || ::setsockopt(fd.get(), SOL_SOCKET, SO_REUSEADDR, &one, sizeof one) != 0 ||
        ::bind(fd.get(), res->ai_addr, res->ai_addrlen) != 0 || ::listen(fd.get(), 64) != 0) {
        Outcome o =
            cannot("cannot listen on " + bind + ":" + service + ": " + std::strerror(errno));
        ::freeaddrinfo(res);
        return o;
    }
    ::freeaddrinfo(res);
    sockaddr_storage sa;
    socklen_t len = sizeof sa;
    ::getsockname(fd.get(), reinterpret_cast<sockaddr *>(&sa), &len);
    bound = ntohs(sa.ss_family == AF_INET6 ? reinterpret_cast<sockaddr_in6 &>(sa).sin6_port
                                           : reinterpret_cast<sockaddr_in &>(sa).sin_port);
    out = std::move(fd);
    return outcome::ok();
}

Outcome open_data_port(fwd::Options options, bool default_port,
                       std::unique_ptr<fwd::Forwarder> &out)
{
    // The Forwarder's constructor binds and starts threads: it throws what it cannot do.
    try {
        out = std::make_unique<fwd::Forwarder>(options);
        return outcome::ok();
    } catch (const std::system_error &e) {
        if (!default_port || e.code().value() != EADDRINUSE)
            return cannot(e.what());
        logf("default data port %u is in use (%s): taking a free one",
             static_cast<unsigned>(options.data_port), e.what());
    } catch (const std::exception &e) {
        return cannot(e.what());
    }
    options.data_port = 0;
    try {
        out = std::make_unique<fwd::Forwarder>(options);
        return outcome::ok();
    } catch (const std::exception &e) {
        return cannot(e.what());
    }
}

} // namespace lnd
