// All supervised processes of the daemon, namespaced by instance: the commands of the
// protocol (spawn, stop, signal, list, output, forget), reaping, timers and the descriptors
// the poll loop watches.  Owns the Process records; knows nothing about connections.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <poll.h>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <utility>
#include <vector>

#include "os.hpp"
#include "outcome.hpp"
#include "process.hpp"
#include "spec.hpp"

namespace lnd {

constexpr size_t kMaxProcesses = 4096; // records, exited ones included

class Supervisor {
public:
    Supervisor(Os &os, Sink &sink) : os_(os), sink_(sink) {}

    // Starts a process: refused at once, or deferred: Sink::spawn_result with `token`
    // follows once the keeper has reported.
    Outcome spawn(const std::string &instance, const SpawnRequest &req, uint64_t token);
    // The instance's process of that name in `found`; refused if there is none.
    Outcome find(const std::string &instance, const std::string &name, Process *&found);
    std::vector<const Process *> list(const std::string &instance) const;
    // The record whose keeper is `keeper`, in any state (nullptr if none).
    Process *find_keeper(pid_t keeper) noexcept;
    // Drops the record of an exited process.
    Outcome forget(const std::string &instance, const std::string &name);

    void reap(); // after SIGCHLD: every exited child
    void tick(); // every poll round
    double next_deadline() const noexcept;

    struct FdRef {
        uint64_t id;
        Process::Fd which;
    };
    void collect_fds(std::vector<pollfd> &fds, std::vector<FdRef> &refs) const;
    void on_fd(const FdRef &ref);

    // Daemon shutdown: STOP for every running process; after kill_all() (the second shutdown
    // signal) SIGKILL instead.  Both hold from then on: tick() applies them to processes whose
    // start is only reported later.
    void stop_all();
    void kill_all();
    size_t alive() const noexcept; // records that have not exited
    // Keepers of refused spawns that have not been reaped yet (they end on their own).
    size_t stray_keepers() const noexcept { return stray_.size(); }
    size_t size() const noexcept { return procs_.size(); }

private:
    using Key = std::pair<std::string, std::string>; // instance, name
    void erase(Process *p);
    void erase_if_failed(Process *p);

    Os &os_;
    Sink &sink_;
    uint64_t next_id_ = 1;
    std::map<Key, std::unique_ptr<Process>> procs_;
    std::unordered_map<uint64_t, Process *> by_id_;
    std::unordered_map<pid_t, Process *> by_keeper_;
    std::unordered_set<pid_t> stray_;
    enum class Shutdown { none, stop, kill } shutdown_ = Shutdown::none;
};

} // namespace lnd
