// The small OS interface of the supervisor (docs/daemon.md, "Process lifecycle"): starting a
// process through its keeper, signalling, reaping and the clocks.  LinuxOs is the real one
// (os_linux.cpp); the unit tests substitute a fake to drive the state machine.
#pragma once

#include <cstdint>
#include <string>
#include <sys/types.h>
#include <vector>

#include "fd.hpp"
#include "outcome.hpp"

namespace lnd {

struct Rlimit {
    int resource;     // RLIMIT_*
    std::string name; // as the request spelled it, for messages
    uint64_t soft;    // RLIM_INFINITY: unlimited
    uint64_t hard;
};

// Everything needed to start one process, already checked (spec.cpp).
struct LaunchSpec {
    std::vector<std::string> argv; // argv[0] is looked up in the PATH of `env`
    std::vector<std::string> env;  // NAME=VALUE, the complete environment
    std::string cwd;               // absolute
    std::vector<Rlimit> rlimits;
    int policy = 0;   // SCHED_*
    int priority = 0; // real-time priority for FIFO/RR, nice value otherwise
    std::vector<int> affinity;
    bool use_pty = true;
    // How the keeper ends the tree by itself when the daemon is gone (as STOP would).
    int term_signal = 15;
    double term_timeout = 5.0;
};

// A started keeper.  It reports on `report` (fixed-size KeeperReport records) and exits
// once nothing of the process tree is left; `out`/`err` are the read ends of the output
// (pty: only `out`, the master).
struct Launched {
    pid_t keeper = -1;
    UniqueFd report;
    UniqueFd out;
    UniqueFd err;
    UniqueFd slave; // pty: the daemon's copy of the slave, closed once the child has it
};

// Where the setup of the child failed (KeeperReport::stage of a `failed` report).
enum class Stage : int32_t {
    setup = 1, // session, terminal or standard streams
    chdir = 2,
    rlimit = 3, // KeeperReport::index says which
    scheduler = 4,
    nice = 5,
    affinity = 6,
    exec = 7,
};

struct KeeperReport {
    enum Kind : int32_t { started = 1, failed = 2, main_exit = 3 };
    int32_t kind;
    int32_t value; // started: pid; failed: Stage; main_exit: wait status
    int32_t index; // failed: which rlimit
    int32_t err;   // failed: errno
};
static_assert(sizeof(KeeperReport) == 16, "a report is written in one piece");

class Os {
public:
    virtual ~Os() = default;
    virtual double monotonic() noexcept = 0; // seconds, for deadlines
    virtual double wall() noexcept = 0;      // seconds since the epoch, for reports
    // Starts the keeper (which starts the process); refused with error spawn_failed.
    virtual Outcome launch(const LaunchSpec &spec, Launched &out) = 0;
    // kill(2); 0 or -errno.
    virtual int kill(pid_t pid, int sig) noexcept = 0;
    // Sends `sig` to every descendant of `keeper` (not the keeper) except members of
    // process group `skip_group` (0: none); how many descendants there were.
    virtual int kill_tree(pid_t keeper, int sig, pid_t skip_group) noexcept = 0;
    // One waitpid(-1, WNOHANG): true and pid/status if a child was reaped.
    virtual bool reap(pid_t &pid, int &status) noexcept = 0;
};

} // namespace lnd
