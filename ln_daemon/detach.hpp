// Detaching the daemon from its terminal at start-up (docs/daemon.md, "Running it"): the
// launcher forks the daemon and waits on a pipe for its verdict, so that a start-up problem
// after the fork (the data port in use, ...) is still the launcher's error and exit status.
#pragma once

#include <string>

#include "fd.hpp"
#include "outcome.hpp"

namespace lnd {

class Detacher {
public:
    // Forks.  In the launcher, `launcher_status` becomes its exit status once the daemon has
    // given its verdict (the listening line is printed for `where`, "ADDR:PORT"); in the
    // daemon it stays -1 and the daemon is in a session of its own, its working directory /.
    Outcome detach(const std::string &where, int &launcher_status);
    // A start-up problem: to the launcher if detached, else "ln_daemon: error: TEXT" on
    // stderr; the exit status.
    int fail(const std::string &text);
    // Start-up is complete: the listening line for `where` (on stdout, or the launcher prints
    // it); a detached daemon's standard streams go to /dev/null, and its log as well unless
    // `keep_log`.
    void started(const std::string &where, unsigned data_port, bool keep_log);

private:
    UniqueFd verdict_; // detached: the pipe to the launcher
};

// "ln_daemon: error: TEXT" on stderr; exit status 1.
int fail(const std::string &text);

} // namespace lnd
