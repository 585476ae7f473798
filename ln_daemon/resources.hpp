// Resource samples of a host and of the processes the daemon runs (docs/daemon.md, "Resource
// samples"): parsers of the /proc files they come from, and the Sampler that reads them once
// per period into an EV_RESOURCES payload, turning counters into rates since the previous
// sample.  The /proc root is a parameter, so tests read fixture trees; buffers are reused, so
// a round allocates nothing once the first has sized them.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <sys/types.h>
#include <unordered_map>
#include <vector>

#include "outcome.hpp"
#include "protocol.hpp"

namespace lnd::res {

struct PidStat {            // /proc/PID/stat
    uint64_t ticks = 0;     // utime + stime, clock ticks
    uint32_t threads = 0;   // num_threads
    uint64_t rss_pages = 0; // rss
};

struct PidStatus { // /proc/PID/status
    uint64_t rss_bytes = 0;
    uint64_t voluntary = 0;
    uint64_t involuntary = 0;
};

struct CpuTicks { // one line of /proc/stat
    uint64_t busy = 0;
    uint64_t total = 0;
};

struct MemInfo { // /proc/meminfo, bytes
    uint64_t total = 0;
    uint64_t available = 0;
    uint64_t swap_total = 0;
    uint64_t swap_free = 0;
};

struct NetBytes { // one interface of /proc/net/dev
    std::string interface;
    uint64_t rx = 0;
    uint64_t tx = 0;
};

struct LoadAvg { // /proc/loadavg
    double one = 0, five = 0, fifteen = 0;
};

// Each parser refuses text it cannot read with an error naming the field; `out` is then
// unspecified.  None of them reads beyond `text`.
Outcome parse_pid_stat(std::string_view text, PidStat &out);
Outcome parse_pid_status(std::string_view text, PidStatus &out);
// `all` is the "cpu" line, `cpus` one entry per "cpuN" line (in file order).
Outcome parse_proc_stat(std::string_view text, CpuTicks &all, std::vector<CpuTicks> &cpus);
Outcome parse_meminfo(std::string_view text, MemInfo &out);
// Reuses the entries of `out` (their strings keep their capacity).
Outcome parse_net_dev(std::string_view text, std::vector<NetBytes> &out);
Outcome parse_loadavg(std::string_view text, LoadAvg &out);

constexpr double kDefaultPeriod = 1.0; // seconds, --resource-period
constexpr double kMinPeriod = 0.1;
constexpr double kMaxPeriod = 3600.0;

class Sampler {
public:
    // `root` is where proc is mounted ("/proc"); `hz` its clock ticks per second.
    explicit Sampler(std::string root = "/proc", long hz = 0);

    // The host's figures into `out` (everything but `processes`); rates over the time since
    // the previous call (`now` is monotonic seconds); 0 at the first call.
    Outcome sample_host(double now, wire::EvResources &out);
    // One process's figures; `cpu` is -1 at its first sample.  An error when the process is
    // gone or its files cannot be read.
    Outcome sample_process(pid_t pid, double now, wire::ProcessResources &out);
    // Forgets the processes not sampled since `before` (monotonic seconds).
    void forget_older(double before);

private:
    Outcome read(const char *what, pid_t pid);
    uint32_t count_fds(pid_t pid);

    struct Previous {
        uint64_t ticks;
        double time;
        double cpu; // the figure it gave
    };
    std::string root_;
    double hz_;
    uint64_t page_;
    bool proc_fs_;          // root_ is a proc file system (not a test's tree)
    std::string buf_;       // the file last read
    std::string_view text_; // its text, in buf_
    std::string path_;      // its path
    CpuTicks all_, prev_all_;
    std::vector<CpuTicks> cpus_, prev_cpus_;
    std::vector<NetBytes> net_, prev_net_;
    double prev_time_ = -1; // of the previous host sample
    std::unordered_map<pid_t, Previous> previous_;
};

} // namespace lnd::res
