// The daemon's process requests (docs/daemon.md, "Protocol"): SPAWN, STOP, FORGET, OUTPUT,
// SIGNAL and LIST, one handler each, carried out on the Supervisor this feature owns.  SPAWN
// is answered later, once the keeper has reported (Sink::spawn_result); the rest at once.
#pragma once

#include <cstdint>
#include <string>

#include "feature.hpp"
#include "os.hpp"
#include "outcome.hpp"
#include "process.hpp"
#include "protocol.hpp"
#include "supervisor.hpp"

namespace lnd {

class Processes final : public Feature {
public:
    // `host_id` becomes LN_HOST_ID of every process that does not name one; `os` and `sink`
    // must outlive this.
    Processes(Os &os, Sink &sink, std::string host_id);

    bool handles(uint8_t type) const noexcept override;
    Outcome handle(const Request &req) override;

    // The daemon's shutdown: SPAWN is refused from now on and every process is stopped.
    void stop_all();
    // What the poll loop drives: descriptors, reaping, timers.
    Supervisor &supervisor() noexcept { return supervisor_; }

private:
    Outcome spawn(const Request &req, SpawnRequest &spawn);
    Outcome stop(const std::string &instance, const wire::Stop &stop);
    Outcome forget(const std::string &instance, const wire::Forget &forget);
    Outcome output(const std::string &instance, const wire::Output &output);
    Outcome signal(const std::string &instance, const wire::Signal &signal);
    Outcome list(const std::string &instance);

    Supervisor supervisor_;
    std::string host_id_;
    bool closing_ = false;
};

} // namespace lnd
