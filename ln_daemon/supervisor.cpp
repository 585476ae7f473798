// The process table of the daemon (supervisor.hpp).  Records are found by (instance, name)
// for commands, by id for descriptors (so a record erased meanwhile is simply skipped) and by
// keeper pid for reaping.
#include "supervisor.hpp"

#include <cerrno>
#include <cmath>
#include <cstring>

#include "log.hpp"

namespace lnd {

Outcome Supervisor::spawn(const std::string &instance, const SpawnRequest &req, uint64_t token)
{
    LaunchSpec launch;
    ProcessConfig config;
    if (Outcome o = check_spawn(req, launch, config); o.failed())
        return o;
    config.instance = instance;
    Key key{instance, req.name};
    auto it = procs_.find(key);
    if (it != procs_.end()) {
        if (it->second->state() != State::exited)
            return outcome::error(
                proto::Err::already_running,
                "process " + req.name + " is already " + state_name(it->second->state()) +
                    (it->second->pid() ? " (pid " + std::to_string(it->second->pid()) + ")"
                                       : std::string()));
        erase(it->second.get()); // a new run replaces the record of the old one
    }
    if (procs_.size() >= kMaxProcesses)
        return outcome::error(proto::Err::limit, "too many processes (" +
                                                     std::to_string(kMaxProcesses) +
                                                     "); forget exited ones first");
    RotatingLog log;
    if (!config.log_path.empty())
        if (Outcome o = log.open(config.log_path, config.log_limit, config.log_keep); o.failed())
            return o;
    Launched launched;
    if (Outcome o = os_.launch(launch, launched); o.failed())
        return o;
    pid_t keeper = launched.keeper;
    auto proc = std::make_unique<Process>(os_, sink_, next_id_++, token, std::move(config),
                                          std::move(launch), std::move(launched), std::move(log));
    Process *p = proc.get();
    by_id_[p->id()] = p;
    by_keeper_[keeper] = p;
    procs_.emplace(std::move(key), std::move(proc));
    return outcome::deferred();
}

Outcome Supervisor::find(const std::string &instance, const std::string &name, Process *&found)
{
    auto it = procs_.find({instance, name});
    // A record still starting belongs to its SPAWN until that is answered.
    if (it == procs_.end() || it->second->state() == State::starting)
        return outcome::error(proto::Err::unknown_process,
                              "no process " + name + " in instance " + instance);
    found = it->second.get();
    return outcome::ok();
}

std::vector<const Process *> Supervisor::list(const std::string &instance) const
{
    std::vector<const Process *> out;
    for (auto it = procs_.lower_bound({instance, std::string()});
         it != procs_.end() && it->first.first == instance; ++it)
        if (it->second->state() != State::starting)
            out.push_back(it->second.get());
    return out;
}

Process *Supervisor::find_keeper(pid_t keeper) noexcept
{
    auto it = by_keeper_.find(keeper);
    return it == by_keeper_.end() ? nullptr : it->second;
}

Outcome Supervisor::forget(const std::string &instance, const std::string &name)
{
    Process *p = nullptr;
    if (Outcome o = find(instance, name, p); o.failed())
        return o;
    if (p->state() != State::exited)
        return outcome::error(proto::Err::still_running, "process " + name + " is " +
                                                             state_name(p->state()) +
                                                             "; stop it first");
    erase(p);
    return outcome::ok();
}

void Supervisor::erase(Process *p)
{
    by_id_.erase(p->id());
    auto k = by_keeper_.find(p->keeper());
    if (k != by_keeper_.end() && k->second == p) {
        by_keeper_.erase(k);
        stray_.insert(p->keeper()); // still to be reaped
    }
    procs_.erase({p->instance(), p->name()});
}

void Supervisor::erase_if_failed(Process *p)
{
    if (p->failed())
        erase(p);
}

void Supervisor::reap()
{
    pid_t pid;
    int status;
    while (os_.reap(pid, status)) {
        auto it = by_keeper_.find(pid);
        if (it == by_keeper_.end()) {
            stray_.erase(pid); // a refused spawn's keeper, or an orphan left to the daemon
            continue;
        }
        Process *p = it->second;
        by_keeper_.erase(it);
        p->on_keeper_exit(status);
        erase_if_failed(p);
    }
}

void Supervisor::tick()
{
    if (shutdown_ == Shutdown::kill)
        kill_all();
    else if (shutdown_ == Shutdown::stop)
        stop_all();
    for (auto &entry : procs_)
        entry.second->tick();
}

double Supervisor::next_deadline() const noexcept
{
    double due = HUGE_VAL;
    for (const auto &entry : procs_)
        due = std::min(due, entry.second->next_deadline());
    return due;
}

void Supervisor::collect_fds(std::vector<pollfd> &fds, std::vector<FdRef> &refs) const
{
    for (const auto &entry : procs_) {
        const Process &p = *entry.second;
        for (Process::Fd which : {Process::Fd::report, Process::Fd::out, Process::Fd::err}) {
            int fd = p.fd(which);
            if (fd >= 0) {
                fds.push_back({fd, POLLIN, 0});
                refs.push_back({p.id(), which});
            }
        }
    }
}

void Supervisor::on_fd(const FdRef &ref)
{
    auto it = by_id_.find(ref.id);
    if (it == by_id_.end())
        return;
    Process *p = it->second;
    p->on_readable(ref.which);
    erase_if_failed(p);
}

void Supervisor::stop_all()
{
    if (shutdown_ == Shutdown::none)
        shutdown_ = Shutdown::stop;
    for (auto &entry : procs_)
        if (entry.second->state() == State::running)
            (void)entry.second->stop(); // a running process is never refused
}

void Supervisor::kill_all()
{
    shutdown_ = Shutdown::kill;
    for (auto &entry : procs_)
        entry.second->kill_now();
}

size_t Supervisor::alive() const noexcept
{
    size_t n = 0;
    for (const auto &entry : procs_)
        n += entry.second->state() != State::exited;
    return n;
}

} // namespace lnd
