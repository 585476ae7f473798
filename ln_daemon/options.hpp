// ln_daemon's command line (docs/daemon.md, "Running it"): the options, their defaults and
// their checks, and the usage text.
#pragma once

#include <cstdint>
#include <string>

#include "outcome.hpp"

namespace lnd {

extern const char kUsage[];

struct Options {
    unsigned port = 0; // TCP port; 0 picks a free one
    std::string bind = "0.0.0.0";
    std::string key_file;
    std::string log_file; // "": stderr
    bool foreground = false;
    unsigned data_port = 0;         // 0 picks a free one
    bool default_data_port = false; // not given: another may be taken if it is in use
    unsigned advertised_port = 0;   // 0: the real data port
    unsigned long udp_fragment = 0;
    unsigned long spin_us = 0;
    uint64_t logger_memory = 0;
    double resource_period = 1.0; // seconds, the default of RESOURCES; 0: refused
    bool help = false;            // --help: print the usage and end
};

// The TCP port from $LN_ARBITER_PORT, else the default, into `port`.
Outcome port_from_environment(unsigned &port);

// Reads the command line into `out` (whose port is the default of --port).  A refusal is a
// usage error whose text main prints with the usage (no text: getopt has said why).
Outcome parse_options(int argc, char **argv, Options &out);

} // namespace lnd
