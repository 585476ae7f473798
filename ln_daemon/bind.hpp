// Binding the daemon's sockets at start-up: the TCP listener for managers, and the data port
// of topic forwarding, which the Forwarder binds (after detaching: its threads would not
// survive the fork).
#pragma once

#include <memory>
#include <string>

#include "fd.hpp"
#include "forward.hpp"
#include "outcome.hpp"

namespace lnd {

// A bound, listening, non-blocking socket on bind:port into `out`; the port actually bound
// goes to `bound` (it differs for port 0).
Outcome listen_on(const std::string &bind, unsigned port, UniqueFd &out, unsigned &bound);

// The Forwarder on `options.data_port` into `out`.  With `default_port` a port in use gives
// way to a free one (logged): the default lies in the range the kernel takes source ports
// of outgoing connections from, and managers learn the real data port from NET_INFO.
Outcome open_data_port(fwd::Options options, bool default_port,
                       std::unique_ptr<fwd::Forwarder> &out);

} // namespace lnd
