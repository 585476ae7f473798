// SendStream: what the stream table knows of a sending stream, whichever its transport:
// start its threads, ask them to stop, join them, read its counters.
#pragma once

#include <string>

#include "forward.hpp"
#include "forward_stats.hpp"

namespace lnd::fwd {

class SendStream {
public:
    explicit SendStream(const SendSpec &spec)
        : spec_(spec), counters_(spec.token, true, spec.transport, spec.transport == Transport::udp)
    {
        bool v6 = spec.host.find(':') != std::string::npos; // an IPv6 literal
        counters_.set_peer((v6 ? "[" + spec.host + "]" : spec.host) + ":" +
                           std::to_string(spec.port));
    }
    virtual ~SendStream() = default;
    SendStream(const SendStream &) = delete;
    SendStream &operator=(const SendStream &) = delete;

    virtual void start() = 0;
    // Asks the threads to stop and returns at once; join() waits for them.  Stopping
    // several streams first and joining them after lets their waits overlap.
    virtual void stop() noexcept = 0;
    virtual void join() noexcept = 0;

    StreamStats stats() const { return counters_.snapshot(); }
    const SendSpec &spec() const noexcept { return spec_; }

protected:
    const SendSpec spec_;
    StreamCounters counters_;
};

} // namespace lnd::fwd
