// Parsing ln_daemon's command line (options.hpp): numbers, ports and byte sizes, each with
// its range, and the data port's default, which follows from --port.
#include "options.hpp"

#include <cerrno>
#include <cstdlib>
#include <getopt.h>

#include "forward.hpp"
#include "loggers.hpp"
#include "resources.hpp"

#include <default_ports.h>

namespace lnd {

const char kUsage[] =
    "usage: ln_daemon [--port P] [--bind ADDR] --key-file FILE [--log FILE] [--foreground]\n"
    "                 [--data-port P] [--advertise-data-port P] [--udp-fragment-size N]\n"
    "                 [--spin-us N] [--logger-memory BYTES] [--resource-period S]\n"
    "\n"
    "Supervises processes for ln_manager instances on this host and forwards topics\n"
    "between hosts (docs/daemon.md).\n"
    "\n"
    "  --port P        TCP port (default: $" LN_DAEMON_PORT_ENV ", else " LN_PORT_TEXT(
        LN_DEFAULT_DAEMON_PORT) "; 0 picks a free one)\n"
                                "  --bind ADDR     address to listen on (default 0.0.0.0), also "
                                "for the data port\n"
                                "  --key-file FILE the shared key: 64 hex digits, mode 0600, owned "
                                "by this user\n"
                                "  --log FILE      append the log here (default: stderr; discarded "
                                "when detached)\n"
                                "  --foreground    do not detach from the terminal\n"
                                "  --data-port P   UDP and TCP port of topic forwarding (default: "
                                "the TCP port + 1;\n"
                                "                  0, and with --port 0, picks a free one)\n"
                                "  --advertise-data-port P\n"
                                "                  the data port managers are told (default: the "
                                "real one; for relays)\n"
                                "  --udp-fragment-size N\n"
                                "                  payload bytes per forwarded UDP datagram, "
                                "256..65000 (default 1368)\n"
                                "  --spin-us N     forwarding polls up to N microseconds for the "
                                "next sample, datagram\n"
                                "                  or frame before sleeping, 0..10000 (default 0; "
                                "lower latency for CPU)\n"
                                "  --logger-memory BYTES\n"
                                "                  memory of all topic loggers together, with k, M "
                                "or G for KiB, MiB,\n"
                                "                  GiB (default 256M; 0 disables topic logging)\n"
                                "  --resource-period S\n"
                                "                  default seconds between resource samples, "
                                "0.1..3600 (default 1;\n"
                                "                  0 disables them)\n";

namespace {

constexpr unsigned kDefaultPort = LN_DEFAULT_DAEMON_PORT;
constexpr unsigned long kMinFragment = 256, kMaxFragment = 65000; // --udp-fragment-size

Outcome usage(std::string text) { return outcome::error(proto::Err::bad_request, std::move(text)); }

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

bool parse_port(const char *text, unsigned long lo, unsigned &port)
{
    unsigned long v;
    if (!parse_number(text, lo, 65535, v))
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

// Seconds of --resource-period: 0, or kMinPeriod..kMaxPeriod.
bool parse_period(const char *text, double &out)
{
    if (*text < '0' || *text > '9')
        return false;
    char *end;
    errno = 0;
    double v = std::strtod(text, &end);
    if (errno || *end || !(v == 0 || (v >= res::kMinPeriod && v <= res::kMaxPeriod)))
        return false;
    out = v;
    return true;
}

} // namespace

Outcome port_from_environment(unsigned &port)
{
    port = kDefaultPort;
    const char *env = std::getenv(LN_DAEMON_PORT_ENV);
    if (env && *env && !parse_port(env, 0, port))
        return outcome::error(proto::Err::bad_request,
                              std::string(LN_DAEMON_PORT_ENV " is not a port number: ") + env);
    return outcome::ok();
}

Outcome parse_options(int argc, char **argv, Options &out)
{
    out.udp_fragment = fwd::Options().udp_payload;
    out.logger_memory = kDefaultLoggerMemory;
    bool data_port_given = false;
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
        {"resource-period", required_argument, nullptr, 'r'},
        {"help", no_argument, nullptr, 'h'},
        {nullptr, 0, nullptr, 0},
    };
    for (int opt; (opt = ::getopt_long(argc, argv, "", options, nullptr)) != -1;) {
        switch (opt) {
        case 'p':
            if (!parse_port(optarg, 0, out.port))
                return usage("--port needs a number 0..65535");
            break;
        case 'b':
            out.bind = optarg;
            break;
        case 'k':
            out.key_file = optarg;
            break;
        case 'l':
            out.log_file = optarg;
            break;
        case 'f':
            out.foreground = true;
            break;
        case 'd':
            if (!parse_port(optarg, 0, out.data_port))
                return usage("--data-port needs a number 0..65535");
            data_port_given = true;
            break;
        case 'a':
            if (!parse_port(optarg, 1, out.advertised_port))
                return usage("--advertise-data-port needs a number 1..65535");
            break;
        case 's':
            if (!parse_number(optarg, kMinFragment, kMaxFragment, out.udp_fragment))
                return usage("--udp-fragment-size needs a number 256..65000");
            break;
        case 'w':
            if (!parse_number(optarg, 0, 10000, out.spin_us))
                return usage("--spin-us needs a number 0..10000");
            break;
        case 'm':
            if (!parse_bytes(optarg, out.logger_memory))
                return usage("--logger-memory needs a number of bytes, optionally with k, M or G "
                             "(e.g. 256M)");
            break;
        case 'r':
            if (!parse_period(optarg, out.resource_period))
                return usage("--resource-period needs seconds 0.1..3600, or 0");
            break;
        case 'h':
            out.help = true;
            return outcome::ok();
        default:
            return usage("");
        }
    }
    if (out.key_file.empty())
        return usage("--key-file is required");
    if (optind != argc)
        return usage("unexpected argument");
    out.default_data_port = !data_port_given;
    if (!data_port_given) {
        if (out.port == 65535)
            return usage("the default data port (--port + 1) would be 65536; give --data-port");
        out.data_port = out.port == 0 ? 0 : out.port + LN_DATA_PORT_OFFSET;
    }
    if (out.port != 0 && out.data_port == out.port)
        return usage("--data-port must differ from --port");
    return outcome::ok();
}

} // namespace lnd
