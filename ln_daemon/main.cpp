// ln_daemon's entry point: options, the key file, the listening socket, detaching from the
// terminal, signal set-up, then the poll loop (server.cpp).  Start-up problems are one line
// "ln_daemon: error: ..." on stderr and exit status 1 (2 for a usage error).
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fcntl.h>
#include <getopt.h>
#include <netdb.h>
#include <string>
#include <sys/prctl.h>
#include <sys/signalfd.h>
#include <sys/socket.h>
#include <unistd.h>

#include "auth.hpp"
#include "fd.hpp"
#include "log.hpp"
#include "os_linux.hpp"
#include "server.hpp"

namespace {

constexpr unsigned kDefaultPort = 54376; // the LN "arbiter" port

const char kUsage[] =
    "usage: ln_daemon [--port P] [--bind ADDR] --key-file FILE [--log FILE] [--foreground]\n"
    "\n"
    "Supervises processes for ln_manager instances on this host (docs/daemon.md).\n"
    "\n"
    "  --port P        TCP port (default: $LN_ARBITER_PORT, else 54376; 0 picks a free one)\n"
    "  --bind ADDR     address to listen on (default 0.0.0.0)\n"
    "  --key-file FILE the shared key: 64 hex digits, mode 0600, owned by this user\n"
    "  --log FILE      append the log here (default: stderr; discarded when detached)\n"
    "  --foreground    do not detach from the terminal\n";

int fail(const std::string &text)
{
    std::fprintf(stderr, "ln_daemon: error: %s\n", text.c_str());
    return 1;
}

bool parse_port(const char *text, unsigned &port)
{
    char *end;
    errno = 0;
    unsigned long v = std::strtoul(text, &end, 10);
    if (errno || !*text || *end || v > 65535)
        return false;
    port = static_cast<unsigned>(v);
    return true;
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
    if (const char *env = std::getenv("LN_ARBITER_PORT"); env && *env) {
        if (!parse_port(env, port))
            return fail(std::string("LN_ARBITER_PORT is not a port number: ") + env);
    }
    std::string bind = "0.0.0.0", key_file, log_file;
    bool foreground = false;
    static const option options[] = {
        {"port", required_argument, nullptr, 'p'},     {"bind", required_argument, nullptr, 'b'},
        {"key-file", required_argument, nullptr, 'k'}, {"log", required_argument, nullptr, 'l'},
        {"foreground", no_argument, nullptr, 'f'},     {"help", no_argument, nullptr, 'h'},
        {nullptr, 0, nullptr, 0},
    };
    for (int opt; (opt = ::getopt_long(argc, argv, "", options, nullptr)) != -1;) {
        switch (opt) {
        case 'p':
            if (!parse_port(optarg, port)) {
                std::fprintf(stderr, "ln_daemon: error: --port needs a number 0..65535\n%s",
                             kUsage);
                return 2;
            }
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
        case 'h':
            std::fputs(kUsage, stdout);
            return 0;
        default:
            std::fputs(kUsage, stderr);
            return 2;
        }
    }
    if (optind != argc || key_file.empty()) {
        std::fprintf(stderr, "ln_daemon: error: %s\n%s",
                     key_file.empty() ? "--key-file is required" : "unexpected argument",
                     kUsage);
        return 2;
    }

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
    if (!foreground) {
        std::fflush(stdout);
        pid_t child = ::fork();
        if (child < 0)
            return fail(std::string("cannot fork: ") + std::strerror(errno));
        if (child > 0) {
            std::printf("ln_daemon: listening on %s:%u (pid %d)\n", bind.c_str(), bound,
                        static_cast<int>(child));
            return 0;
        }
        ::setsid();
        if (::chdir("/") != 0)
            return 1;
        redirect_stdio_to_null();
        if (log_file.empty())
            lnd::log_discard();
    } else {
        std::printf("ln_daemon: listening on %s:%u (pid %d)\n", bind.c_str(), bound,
                    static_cast<int>(::getpid()));
        std::fflush(stdout);
    }

    // Orphans whose keeper was killed come to us rather than to init.
    ::prctl(PR_SET_CHILD_SUBREAPER, 1);
    sigset_t mask;
    sigemptyset(&mask);
    for (int sig : {SIGCHLD, SIGTERM, SIGINT, SIGHUP})
        sigaddset(&mask, sig);
    ::sigprocmask(SIG_BLOCK, &mask, nullptr);
    lnd::UniqueFd signals(::signalfd(-1, &mask, SFD_NONBLOCK | SFD_CLOEXEC));
    if (!signals) {
        lnd::logf("signalfd: %s", std::strerror(errno));
        return 1;
    }
    lnd::logf("listening on %s:%u, key file %s", bind.c_str(), bound, key_file.c_str());
    lnd::LinuxOs os;
    lnd::Server server(os, key, std::move(listener), std::move(signals), log_file);
    return server.run();
}
