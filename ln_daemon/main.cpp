// ln_daemon's entry point: options, the key file, the listening socket, detaching from the
// terminal, signal set-up, the Forwarder's data port, the loggers' memory limit, then the
// poll loop (server.cpp).
// Start-up problems are one line "ln_daemon: error: ..." on stderr and exit status 1 (2 for
// a usage error); a detaching daemon reports them through a pipe before its launcher exits.
#include <cerrno>
#include <cinttypes>
#include <cstdint>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fcntl.h>
#include <getopt.h>
#include <ln/ln.h>
#include <ln_admin.h>
#include <memory>
#include <netdb.h>
#include <string>
#include <sys/prctl.h>
#include <sys/signalfd.h>
#include <sys/socket.h>
#include <system_error>
#include <unistd.h>

#include "auth.hpp"
#include "fd.hpp"
#include "forward.hpp"
#include "log.hpp"
#include "loggers.hpp"
#include "pulls.hpp"
#include "network.hpp"
#include "os_linux.hpp"
#include "server.hpp"

#include <default_ports.h>

namespace {

constexpr unsigned kDefaultPort = LN_DEFAULT_DAEMON_PORT;

constexpr size_t kMinFragment = 256, kMaxFragment = 65000; // --udp-fragment-size

const char kUsage[] =
    "usage: ln_daemon [--port P] [--bind ADDR] --key-file FILE [--log FILE] [--foreground]\n"
    "                 [--data-port P] [--advertise-data-port P] [--udp-fragment-size N]\n"
    "                 [--spin-us N] [--logger-memory BYTES]\n"
    "\n"
    "Supervises processes for ln_manager instances on this host and forwards topics\n"
    "between hosts (docs/daemon.md).\n"
    "\n"
    "  --port P        TCP port (default: $" LN_DAEMON_PORT_ENV ", else "
    LN_PORT_TEXT(LN_DEFAULT_DAEMON_PORT) "; 0 picks a free one)\n"
    "  --bind ADDR     address to listen on (default 0.0.0.0), also for the data port\n"
    "  --key-file FILE the shared key: 64 hex digits, mode 0600, owned by this user\n"
    "  --log FILE      append the log here (default: stderr; discarded when detached)\n"
    "  --foreground    do not detach from the terminal\n"
    "  --data-port P   UDP and TCP port of topic forwarding (default: the TCP port + 1;\n"
    "                  0, and with --port 0, picks a free one)\n"
    "  --advertise-data-port P\n"
    "                  the data port managers are told (default: the real one; for relays)\n"
    "  --udp-fragment-size N\n"
    "                  payload bytes per forwarded UDP datagram, 256..65000 (default 1400)\n"
    "  --spin-us N     forwarding polls up to N microseconds for the next sample, datagram\n"
    "                  or frame before sleeping, 0..10000 (default 0; lower latency for CPU)\n"
    "  --logger-memory BYTES\n"
    "                  memory of all topic loggers together, with k, M or G for KiB, MiB,\n"
    "                  GiB (default 256M; 0 disables topic logging)\n";

int fail(const std::string &text)
{
    std::fprintf(stderr, "ln_daemon: error: %s\n", text.c_str());
    return 1;
}

bool parse_number(const char *text, unsigned long lo, unsigned long hi, unsigned long &out)
{
    char *end;
    errno = 0;
    unsigned long v = std::strtoul(text, &end, 10);
    if (errno || !*text || *end || *text == '-' || v < lo || v > hi)
        return false;
    out = v;
    return true;
}

bool parse_port(const char *text, unsigned &port)
{
    unsigned long v;
    if (!parse_number(text, 0, 65535, v))
        return false;
    port = static_cast<unsigned>(v);
    return true;
}

// BYTES with an optional binary suffix k/K, m/M or g/G ("256M").
bool parse_bytes(const char *text, uint64_t &out)
{
    if (*text < '0' || *text > '9') // strtoull would take a sign or white space
        return false;
    char *end;
    errno = 0;
    unsigned long long v = std::strtoull(text, &end, 10);
    if (errno)
        return false;
    unsigned shift = 0;
    switch (*end) {
    case '\0':
        break;
    case 'k':
    case 'K':
        shift = 10;
        break;
    case 'm':
    case 'M':
        shift = 20;
        break;
    case 'g':
    case 'G':
        shift = 30;
        break;
    default:
        return false;
    }
    if (*end && end[1])
        return false;
    if (shift && v > (UINT64_MAX >> shift))
        return false;
    out = static_cast<uint64_t>(v) << shift;
    return true;
}

int usage_error(const char *text)
{
    std::fprintf(stderr, "ln_daemon: error: %s\n%s", text, kUsage);
    return 2;
}

// A bound, listening, non-blocking socket on bind:port; the port actually bound goes to
// `bound` (it differs for port 0).
lnd::UniqueFd listen_on(const std::string &bind, unsigned port, unsigned &bound,
                        std::string &error)
{
    addrinfo hints = {};
    hints.ai_family = AF_UNSPEC;
    hints.ai_socktype = SOCK_STREAM;
    hints.ai_flags = AI_PASSIVE | AI_NUMERICSERV;
    addrinfo *res = nullptr;
    std::string service = std::to_string(port);
    int rc = ::getaddrinfo(bind.c_str(), service.c_str(), &hints, &res);
    if (rc != 0) {
        error = "cannot resolve bind address '" + bind + "': " + ::gai_strerror(rc);
        return {};
    }
    lnd::UniqueFd fd(::socket(res->ai_family, SOCK_STREAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0));
    int one = 1;
    if (!fd || ::setsockopt(fd.get(), SOL_SOCKET, SO_REUSEADDR, &one, sizeof one) != 0 ||
        ::bind(fd.get(), res->ai_addr, res->ai_addrlen) != 0 || ::listen(fd.get(), 64) != 0) {
        error = "cannot listen on " + bind + ":" + service + ": " + std::strerror(errno);
        ::freeaddrinfo(res);
        return {};
    }
    ::freeaddrinfo(res);
    sockaddr_storage sa;
    socklen_t len = sizeof sa;
    ::getsockname(fd.get(), reinterpret_cast<sockaddr *>(&sa), &len);
    bound = ntohs(sa.ss_family == AF_INET6 ? reinterpret_cast<sockaddr_in6 &>(sa).sin6_port
                                           : reinterpret_cast<sockaddr_in &>(sa).sin_port);
    return fd;
}

// The launcher of a detaching daemon waits for the daemon's verdict on this pipe: "ok"
// and the data port, or "error" and the text.  EOF without either: the daemon died.
void report_start(int fd, const std::string &verdict) noexcept
{
    const char *p = verdict.data();
    size_t left = verdict.size();
    while (left > 0) {
        ssize_t n = ::write(fd, p, left);
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0)
            return;
        p += n;
        left -= static_cast<size_t>(n);
    }
}

std::string read_verdict(int fd)
{
    std::string text;
    char buf[512];
    for (;;) {
        ssize_t n = ::read(fd, buf, sizeof buf);
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0)
            return text;
        text.append(buf, static_cast<size_t>(n));
    }
}

void redirect_stdio_to_null()
{
    lnd::UniqueFd null_fd(::open("/dev/null", O_RDWR | O_CLOEXEC));
    for (int target = 0; null_fd && target <= 2; ++target)
        ::dup2(null_fd.get(), target); // dup2 clears close-on-exec on the copies
    if (null_fd.get() <= 2)
        null_fd.release(); // it is one of the standard streams now
}

} // namespace

int main(int argc, char **argv)
{
    unsigned port = kDefaultPort;
    if (const char *env = std::getenv(LN_DAEMON_PORT_ENV); env && *env) {
        if (!parse_port(env, port))
            return fail(std::string(LN_DAEMON_PORT_ENV " is not a port number: ") + env);
    }
    std::string bind = "0.0.0.0", key_file, log_file;
    bool foreground = false;
    long data_port = -1, advertised_port = -1; // -1: the default
    unsigned long fragment = lnd::fwd::Options().udp_payload;
    unsigned long spin_us = 0;
    uint64_t logger_memory = lnd::kDefaultLoggerMemory;
    static const option options[] = {
        {"port", required_argument, nullptr, 'p'},
        {"bind", required_argument, nullptr, 'b'},
        {"key-file", required_argument, nullptr, 'k'},
        {"log", required_argument, nullptr, 'l'},
        {"foreground", no_argument, nullptr, 'f'},
        {"data-port", required_argument, nullptr, 'd'},
        {"advertise-data-port", required_argument, nullptr, 'a'},
        {"udp-fragment-size", required_argument, nullptr, 's'},
        {"spin-us", required_argument, nullptr, 'w'},
        {"logger-memory", required_argument, nullptr, 'm'},
        {"help", no_argument, nullptr, 'h'},
        {nullptr, 0, nullptr, 0},
    };
    for (int opt; (opt = ::getopt_long(argc, argv, "", options, nullptr)) != -1;) {
        unsigned long v = 0;
        switch (opt) {
        case 'p':
            if (!parse_port(optarg, port))
                return usage_error("--port needs a number 0..65535");
            break;
        case 'b':
            bind = optarg;
            break;
        case 'k':
            key_file = optarg;
            break;
        case 'l':
            log_file = optarg;
            break;
        case 'f':
            foreground = true;
            break;
        case 'd':
            if (!parse_number(optarg, 0, 65535, v))
                return usage_error("--data-port needs a number 0..65535");
            data_port = static_cast<long>(v);
            break;
        case 'a':
            if (!parse_number(optarg, 1, 65535, v))
                return usage_error("--advertise-data-port needs a number 1..65535");
            advertised_port = static_cast<long>(v);
            break;
        case 's':
            if (!parse_number(optarg, kMinFragment, kMaxFragment, fragment))
                return usage_error("--udp-fragment-size needs a number 256..65000");
            break;
        case 'w':
            if (!parse_number(optarg, 0, 10000, spin_us))
                return usage_error("--spin-us needs a number 0..10000");
            break;
        case 'm':
            if (!parse_bytes(optarg, logger_memory))
                return usage_error("--logger-memory needs a number of bytes, optionally with "
                                   "k, M or G (e.g. 256M)");
            break;
        case 'h':
            std::fputs(kUsage, stdout);
            return 0;
        default:
            std::fputs(kUsage, stderr);
            return 2;
        }
    }
    if (key_file.empty())
        return usage_error("--key-file is required");
    if (optind != argc)
        return usage_error("unexpected argument");
    const bool default_data_port = data_port < 0;
    if (data_port < 0) {
        if (port == 65535)
            return usage_error("the default data port (--port + 1) would be 65536; give "
                               "--data-port");
        data_port = port == 0 ? 0 : port + LN_DATA_PORT_OFFSET;
    }
    if (port != 0 && data_port == static_cast<long>(port))
        return usage_error("--data-port must differ from --port");

    if (!lnd::crypto_init())
        return fail("libsodium cannot be initialised");
    lnd::Key key;
    std::string error;
    if (!lnd::load_key_file(key_file, key, error))
        return fail(error);
    if (!log_file.empty() && !lnd::log_open(log_file, error))
        return fail(error);
    unsigned bound = 0;
    lnd::UniqueFd listener = listen_on(bind, port, bound, error);
    if (!listener)
        return fail(error);

    std::signal(SIGPIPE, SIG_IGN);
    // Blocked before any thread starts, so the Forwarder's threads inherit the mask and these
    // signals only ever arrive through the signalfd of the poll loop.
    sigset_t mask;
    sigemptyset(&mask);
    for (int sig : {SIGCHLD, SIGTERM, SIGINT, SIGHUP})
        sigaddset(&mask, sig);
    ::sigprocmask(SIG_BLOCK, &mask, nullptr);

    lnd::UniqueFd verdict; // detaching: the pipe to the launcher
    if (!foreground) {
        int fds[2];
        if (::pipe2(fds, O_CLOEXEC) != 0)
            return fail(std::string("cannot create a pipe: ") + std::strerror(errno));
        lnd::UniqueFd verdict_r(fds[0]), verdict_w(fds[1]);
        std::fflush(stdout);
        pid_t child = ::fork();
        if (child < 0)
            return fail(std::string("cannot fork: ") + std::strerror(errno));
        if (child > 0) {
            verdict_w.reset();
            std::string text = read_verdict(verdict_r.get());
            if (text.rfind("ok ", 0) == 0) {
                std::printf("ln_daemon: listening on %s:%u (pid %d), data port %s\n",
                            bind.c_str(), bound, static_cast<int>(child), text.c_str() + 3);
                return 0;
            }
            if (text.rfind("error ", 0) == 0)
                return fail(text.substr(6));
            return fail("the daemon ended during start-up");
        }
        verdict_r.reset();
        verdict = std::move(verdict_w);
        ::setsid();
    }
    auto start_failed = [&](const std::string &text) {
        if (!verdict)
            return fail(text);
        report_start(verdict.get(), "error " + text);
        return 1;
    };
    if (!foreground && ::chdir("/") != 0)
        return start_failed(std::string("cannot change to /: ") + std::strerror(errno));

    // The Forwarder runs threads, which do not survive fork(): it starts in the daemon
    // process itself, after detaching.
    lnd::fwd::Options fwd_options;
    fwd_options.bind_address = bind;
    fwd_options.data_port = static_cast<uint16_t>(data_port);
    fwd_options.udp_payload = fragment;
    fwd_options.spin_us = static_cast<unsigned>(spin_us);
    std::unique_ptr<lnd::fwd::Forwarder> forwarder;
    try {
        forwarder = std::make_unique<lnd::fwd::Forwarder>(fwd_options);
    } catch (const std::system_error &e) {
        // The default (port + 1) lies in the range the kernel takes source ports of outgoing
        // connections from; one of them may hold it.  Managers ask for the real data port
        // (NET_INFO), so another one does as well; a port given with --data-port does not.
        if (!default_data_port || e.code().value() != EADDRINUSE)
            return start_failed(e.what());
        lnd::logf("default data port %ld is in use (%s): taking a free one", data_port,
                  e.what());
        fwd_options.data_port = 0;
        try {
            forwarder = std::make_unique<lnd::fwd::Forwarder>(fwd_options);
        } catch (const std::exception &again) {
            return start_failed(again.what());
        }
    } catch (const std::exception &e) {
        return start_failed(e.what());
    }
    unsigned real_data_port = forwarder->data_port();
    unsigned advertised = advertised_port > 0 ? static_cast<unsigned>(advertised_port)
                                              : real_data_port;
    char host_id[256];
    ln_host_id(host_id, sizeof host_id);

    // Orphans whose keeper was killed come to us rather than to init.
    ::prctl(PR_SET_CHILD_SUBREAPER, 1);
    lnd::UniqueFd signals(::signalfd(-1, &mask, SFD_NONBLOCK | SFD_CLOEXEC));
    if (!signals)
        return start_failed(std::string("signalfd: ") + std::strerror(errno));

    if (verdict) {
        report_start(verdict.get(), "ok " + std::to_string(real_data_port));
        verdict.reset();
        redirect_stdio_to_null();
        if (log_file.empty())
            lnd::log_discard();
    } else {
        std::printf("ln_daemon: listening on %s:%u (pid %d), data port %u\n", bind.c_str(), bound,
                    static_cast<int>(::getpid()), real_data_port);
        std::fflush(stdout);
    }
    lnd::logf("listening on %s:%u, data port %u (advertised %u), host id %s, key file %s, "
              "logger memory %" PRIu64 " bytes",
              bind.c_str(), bound, real_data_port, advertised, host_id, key_file.c_str(),
              logger_memory);
    lnd::LinuxOs os;
    lnd::NetCommands net(host_id, static_cast<uint16_t>(advertised), *forwarder);
    lnd::Loggers loggers(logger_memory);
    lnd::Pulls pulls;
    lnd::Server server(os, key, std::move(listener), std::move(signals), log_file, net, loggers,
                       pulls);
    return server.run();
}
