// ln_daemon's entry point: options (options.cpp), the key file, the listening socket
// (bind.cpp), detaching from the terminal (detach.cpp), signal set-up, the Forwarder's data
// port, then the features and the poll loop (server.cpp).
// Start-up problems are one line "ln_daemon: error: ..." on stderr and exit status 1 (2 for
// a usage error); a detaching daemon reports them through a pipe before its launcher exits.
#include <cerrno>
#include <cinttypes>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <ln_admin.h>
#include <memory>
#include <string>
#include <sys/prctl.h>
#include <sys/signalfd.h>
#include <vector>

#include "auth.hpp"
#include "bind.hpp"
#include "detach.hpp"
#include "log.hpp"
#include "loggers.hpp"
#include "network.hpp"
#include "options.hpp"
#include "os_linux.hpp"
#include "pulls.hpp"
#include "server.hpp"

namespace {

int usage_error(const std::string &text)
{
    if (text.empty())
        std::fputs(lnd::kUsage, stderr);
    else
        std::fprintf(stderr, "ln_daemon: error: %s\n%s", text.c_str(), lnd::kUsage);
    return 2;
}

// Blocked before any thread starts, so the Forwarder's threads inherit the mask and these
// signals only ever arrive through the signalfd of the poll loop.
sigset_t block_signals()
{
    std::signal(SIGPIPE, SIG_IGN);
    sigset_t mask;
    sigemptyset(&mask);
    for (int sig : {SIGCHLD, SIGTERM, SIGINT, SIGHUP})
        sigaddset(&mask, sig);
    ::sigprocmask(SIG_BLOCK, &mask, nullptr);
    return mask;
}

} // namespace

int main(int argc, char **argv)
{
    using lnd::Outcome;
    lnd::Options opt;
    if (Outcome o = lnd::port_from_environment(opt.port); o.failed())
        return lnd::fail(o.text);
    if (Outcome o = lnd::parse_options(argc, argv, opt); o.failed())
        return usage_error(o.text);
    if (opt.help) {
        std::fputs(lnd::kUsage, stdout);
        return 0;
    }

    if (!lnd::crypto_init())
        return lnd::fail("libsodium cannot be initialised");
    lnd::Key key;
    if (Outcome o = lnd::load_key_file(opt.key_file, key); o.failed())
        return lnd::fail(o.text);
    if (!opt.log_file.empty())
        if (Outcome o = lnd::log_open(opt.log_file); o.failed())
            return lnd::fail(o.text);
    lnd::UniqueFd listener;
    unsigned bound = 0;
    if (Outcome o = lnd::listen_on(opt.bind, opt.port, listener, bound); o.failed())
        return lnd::fail(o.text);
    const std::string where = opt.bind + ":" + std::to_string(bound);
    sigset_t mask = block_signals();

    lnd::Detacher detacher;
    if (!opt.foreground) {
        int launcher_status = -1;
        if (Outcome o = detacher.detach(where, launcher_status); o.failed())
            return detacher.fail(o.text);
        if (launcher_status >= 0)
            return launcher_status;
    }
    lnd::fwd::Options fwd_options;
    fwd_options.bind_address = opt.bind;
    fwd_options.data_port = static_cast<uint16_t>(opt.data_port);
    fwd_options.udp_payload = opt.udp_fragment;
    fwd_options.spin_us = static_cast<unsigned>(opt.spin_us);
    fwd_options.key = key;
    std::unique_ptr<lnd::fwd::Forwarder> forwarder;
    if (Outcome o = lnd::open_data_port(fwd_options, opt.default_data_port, forwarder); o.failed())
        return detacher.fail(o.text);
    unsigned data_port = forwarder->data_port();
    unsigned advertised = opt.advertised_port ? opt.advertised_port : data_port;
    char host_id[256];
    ln_host_id(host_id, sizeof host_id);

    // Orphans whose keeper was killed come to us rather than to init.
    ::prctl(PR_SET_CHILD_SUBREAPER, 1);
    lnd::UniqueFd signals(::signalfd(-1, &mask, SFD_NONBLOCK | SFD_CLOEXEC));
    if (!signals)
        return detacher.fail(std::string("signalfd: ") + std::strerror(errno));
    detacher.started(where, data_port, !opt.log_file.empty());
    lnd::logf("listening on %s, data port %u (advertised %u), host id %s, key file %s "
              "(key %s), logger memory %" PRIu64 " bytes",
              where.c_str(), data_port, advertised, host_id, opt.key_file.c_str(),
              lnd::key_id(key).c_str(), opt.logger_memory);

    lnd::LinuxOs os;
    lnd::NetCommands net(host_id, static_cast<uint16_t>(advertised), *forwarder);
    lnd::Loggers loggers(opt.logger_memory);
    lnd::Pulls pulls;
    lnd::Server server(os, key, std::move(listener), std::move(signals), opt.log_file, host_id,
                       {&net, &loggers, &pulls}, opt.resource_period);
    lnd::fwd::Forwarder &fwd = *forwarder;
    server.reload_key_on_hangup(opt.key_file, [&fwd](const lnd::Key &k) {
        if (Outcome o = fwd.set_key(k); o.failed())
            lnd::logf("after the key change: %s", o.text.c_str());
    });
    return server.run();
}
