// What every part of the daemon that answers requests offers the server: processes, network
// (rings and streams), topic loggers and pull topics.  The server hands each authenticated
// request to the one feature whose handles() takes its message type and sends the Outcome;
// at the daemon's shutdown it stops every feature's threads.
#pragma once

#include <cstdint>
#include <string>

#include "outcome.hpp"
#include "protocol.hpp"

namespace lnd {

// One request as a feature sees it.
struct Request {
    const std::string &instance; // of the connection that sent it
    uint8_t type;                // proto::Msg
    uint64_t id;                 // unique in this daemon; a deferred answer names it
    proto::Reader &body;
};

class Feature {
public:
    virtual ~Feature() = default;
    // True for the message types handle() takes.
    virtual bool handles(uint8_t type) const noexcept = 0;
    virtual Outcome handle(const Request &req) = 0;
    // Stops the feature's threads and waits for them (the daemon's shutdown).
    virtual void shutdown() noexcept {}
};

} // namespace lnd
