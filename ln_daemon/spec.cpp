// Checking of SPAWN requests (spec.hpp) and the wording of child setup failures.  Checks
// that the kernel would make anyway (permissions, existing CPUs) are left to the child,
// whose errno comes back through the keeper.
#include "spec.hpp"

#include <cerrno>
#include <climits>
#include <cmath>
#include <csignal>
#include <cstring>
#include <sched.h>
#include <strings.h>
#include <sys/resource.h>

namespace lnd {

namespace {

Outcome invalid(std::string text)
{
    return outcome::error(proto::Err::invalid_spec, std::move(text));
}

struct NamedLimit {
    const char *name;
    int resource;
};

constexpr NamedLimit kLimits[] = {
    {"as", RLIMIT_AS},           {"core", RLIMIT_CORE},         {"cpu", RLIMIT_CPU},
    {"data", RLIMIT_DATA},       {"fsize", RLIMIT_FSIZE},       {"locks", RLIMIT_LOCKS},
    {"memlock", RLIMIT_MEMLOCK}, {"msgqueue", RLIMIT_MSGQUEUE}, {"nice", RLIMIT_NICE},
    {"nofile", RLIMIT_NOFILE},   {"nproc", RLIMIT_NPROC},       {"rss", RLIMIT_RSS},
    {"rtprio", RLIMIT_RTPRIO},   {"rttime", RLIMIT_RTTIME},     {"sigpending", RLIMIT_SIGPENDING},
    {"stack", RLIMIT_STACK},
};

struct NamedPolicy {
    const char *name;
    int policy;
};

constexpr NamedPolicy kPolicies[] = {
    {"SCHED_OTHER", SCHED_OTHER}, {"SCHED_BATCH", SCHED_BATCH}, {"SCHED_IDLE", SCHED_IDLE},
    {"SCHED_FIFO", SCHED_FIFO},   {"SCHED_RR", SCHED_RR},
};

// "nofile", "NOFILE" and "RLIMIT_NOFILE" all name RLIMIT_NOFILE.
int find_limit(const std::string &name) noexcept
{
    const char *n = name.c_str();
    if (strncasecmp(n, "RLIMIT_", 7) == 0)
        n += 7;
    for (const auto &l : kLimits)
        if (strcasecmp(n, l.name) == 0)
            return l.resource;
    return -1;
}

// "SCHED_FIFO", "sched_fifo" and "fifo" all name SCHED_FIFO.
int find_policy(const std::string &name) noexcept
{
    const char *n = name.c_str();
    if (strncasecmp(n, "SCHED_", 6) == 0)
        n += 6;
    for (const auto &p : kPolicies)
        if (strcasecmp(n, p.name + 6) == 0)
            return p.policy;
    return -1;
}

bool has_nul(const std::string &s) noexcept { return s.find('\0') != std::string::npos; }

std::string limit_value(uint64_t v)
{
    return v == RLIM_INFINITY ? std::string("unlimited") : std::to_string(v);
}

} // namespace

bool valid_name(const std::string &s) noexcept
{
    if (s.empty() || s.size() > 255)
        return false;
    for (unsigned char c : s)
        if (c < 0x20 || c == 0x7f)
            return false;
    return true;
}

void env_default(std::vector<std::string> &env, const std::string &name, const std::string &value)
{
    for (const auto &e : env)
        if (e.size() > name.size() && e[name.size()] == '=' && e.compare(0, name.size(), name) == 0)
            return;
    env.push_back(name + "=" + value);
}

const char *policy_name(int policy) noexcept
{
    for (const auto &p : kPolicies)
        if (p.policy == policy)
            return p.name;
    return "unknown policy";
}

Outcome check_spawn(const SpawnRequest &req, LaunchSpec &launch, ProcessConfig &config)
{
    if (!valid_name(req.name))
        return invalid(
            "invalid process name: it must be 1 to 255 bytes without control characters");
    if (req.argv.empty() || req.argv[0].empty())
        return invalid("empty command");
    if (req.shell && req.argv.size() != 1)
        return invalid("a shell command is one string, got " + std::to_string(req.argv.size()));
    for (const auto &a : req.argv)
        if (has_nul(a))
            return invalid("the command contains a NUL byte");
    for (const auto &e : req.env) {
        size_t eq = e.find('=');
        if (eq == 0 || eq == std::string::npos || has_nul(e))
            return invalid("invalid environment entry '" + e.substr(0, 64) +
                           "': it must be NAME=VALUE without NUL bytes");
    }
    launch.argv = req.shell ? std::vector<std::string>{"/bin/sh", "-c", req.argv[0]} : req.argv;
    launch.env = req.env;

    launch.cwd = req.cwd.empty() ? "/" : req.cwd;
    if (launch.cwd[0] != '/' || has_nul(launch.cwd))
        return invalid("working directory '" + req.cwd + "' is not an absolute path");

    launch.rlimits.clear();
    for (const auto &r : req.rlimits) {
        int resource = find_limit(r.name);
        if (resource < 0)
            return invalid("unknown resource limit '" + r.name +
                           "' (known: as, core, cpu, data, fsize, locks, memlock, msgqueue, nice, "
                           "nofile, nproc, rss, rtprio, rttime, sigpending, stack)");
        if (r.soft < -1 || r.hard < -1)
            return invalid("resource limit " + r.name + ": negative value (use unlimited)");
        uint64_t soft = r.soft < 0 ? RLIM_INFINITY : static_cast<uint64_t>(r.soft);
        uint64_t hard = r.hard < 0 ? RLIM_INFINITY : static_cast<uint64_t>(r.hard);
        if (hard != RLIM_INFINITY && (soft == RLIM_INFINITY || soft > hard))
            return invalid("resource limit " + r.name + ": soft limit " + limit_value(soft) +
                           " is above the hard limit " + limit_value(hard));
        launch.rlimits.push_back({resource, r.name, soft, hard});
    }

    launch.policy = find_policy(req.policy);
    if (launch.policy < 0)
        return invalid("unknown scheduling policy '" + req.policy +
                       "' (known: SCHED_OTHER, SCHED_BATCH, SCHED_IDLE, SCHED_FIFO, SCHED_RR)");
    launch.priority = req.priority;
    if (launch.policy == SCHED_FIFO || launch.policy == SCHED_RR) {
        int lo = sched_get_priority_min(launch.policy), hi = sched_get_priority_max(launch.policy);
        if (req.priority < lo || req.priority > hi)
            return invalid("priority " + std::to_string(req.priority) + " is out of range for " +
                           policy_name(launch.policy) + " (" + std::to_string(lo) + ".." +
                           std::to_string(hi) + ")");
    } else if (req.priority < -20 || req.priority > 19) {
        return invalid("nice value " + std::to_string(req.priority) + " is out of range for " +
                       policy_name(launch.policy) + " (-20..19)");
    }

    launch.affinity.clear();
    for (uint32_t cpu : req.affinity) {
        if (cpu >= CPU_SETSIZE)
            return invalid("CPU " + std::to_string(cpu) +
                           " in the affinity list is out of range (0.." +
                           std::to_string(CPU_SETSIZE - 1) + ")");
        launch.affinity.push_back(static_cast<int>(cpu));
    }
    launch.use_pty = req.use_pty;

    if (req.max_output_lines > kMaxOutputLines)
        return invalid("max_output_lines " + std::to_string(req.max_output_lines) +
                       " is above the limit of " + std::to_string(kMaxOutputLines));
    if (!req.log_path.empty() && (req.log_path[0] != '/' || has_nul(req.log_path)))
        return invalid("output log path '" + req.log_path + "' is not an absolute path");
    if (req.log_keep > kMaxLogKeep)
        return invalid("output log keep count " + std::to_string(req.log_keep) +
                       " is above the limit of " + std::to_string(kMaxLogKeep));
    if (req.term_signal < 1 || req.term_signal >= NSIG || req.term_signal == SIGSTOP)
        return invalid("invalid term signal " + std::to_string(req.term_signal));
    if (!std::isfinite(req.term_timeout) || req.term_timeout < 0 || req.term_timeout > 1e6)
        return invalid("term timeout must be between 0 and 1e6 seconds");

    launch.term_signal = req.term_signal;
    launch.term_timeout = req.term_timeout;
    config.name = req.name;
    config.max_output_lines = req.max_output_lines;
    config.log_path = req.log_path;
    config.log_limit = req.log_limit;
    config.log_keep = req.log_keep;
    config.term_signal = req.term_signal;
    config.term_timeout = req.term_timeout;
    return outcome::ok();
}

std::string describe_failure(const LaunchSpec &spec, int32_t stage, int32_t index, int32_t err)
{
    std::string why = std::strerror(err);
    switch (static_cast<Stage>(stage)) {
    case Stage::setup:
        return "cannot set up the process's session and output: " + why;
    case Stage::chdir:
        return "cannot change directory to '" + spec.cwd + "': " + why;
    case Stage::rlimit:
        if (index >= 0 && static_cast<size_t>(index) < spec.rlimits.size()) {
            const Rlimit &r = spec.rlimits[static_cast<size_t>(index)];
            return "cannot set resource limit " + r.name + " (soft " + limit_value(r.soft) +
                   ", hard " + limit_value(r.hard) + "): " + why;
        }
        return "cannot set a resource limit: " + why;
    case Stage::scheduler: {
        std::string text = std::string("cannot set scheduling policy ") + policy_name(spec.policy) +
                           " with priority " + std::to_string(spec.priority) + ": " + why;
        if (err == EPERM)
            text += " (needs root, CAP_SYS_NICE or a large enough RLIMIT_RTPRIO, and real-time "
                    "runtime in the daemon's cgroup)";
        return text;
    }
    case Stage::nice: {
        std::string text = "cannot set nice value " + std::to_string(spec.priority) + ": " + why;
        if (err == EPERM || err == EACCES)
            text += " (negative values need root, CAP_SYS_NICE or RLIMIT_NICE)";
        return text;
    }
    case Stage::affinity: {
        std::string cpus;
        for (int c : spec.affinity)
            cpus += (cpus.empty() ? "" : ",") + std::to_string(c);
        return "cannot set CPU affinity to [" + cpus + "]: " + why;
    }
    case Stage::exec: {
        const std::string &file = spec.argv[0];
        if (err == ENOENT && file.find('/') == std::string::npos)
            return "command not found: " + file;
        return "cannot execute '" + file + "': " + why;
    }
    }
    return "process setup failed: " + why;
}

} // namespace lnd
