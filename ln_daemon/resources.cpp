// The /proc parsers and the Sampler of resources.hpp.  Numbers are read by hand from the
// text (no strtod: a string_view need not end in a NUL), each file with one open/read/close
// into a buffer that is kept.
#include "resources.hpp"

#include <cerrno>
#include <cstring>
#include <dirent.h>
#include <fcntl.h>
#include <linux/magic.h>
#include <sys/stat.h>
#include <sys/statfs.h>
#include <unistd.h>

namespace lnd::res {

namespace {

using proto::Err;

Outcome bad(const char *file, const char *what)
{
    return outcome::error(Err::os_error, std::string(file) + ": cannot read " + what);
}

// A cursor over one file's text.
struct Scan {
    std::string_view s;
    size_t i = 0;

    bool end() const noexcept { return i >= s.size(); }
    void blanks() noexcept
    {
        while (i < s.size() && (s[i] == ' ' || s[i] == '\t'))
            ++i;
    }
    bool u64(uint64_t &v) noexcept
    {
        blanks();
        size_t start = i;
        v = 0;
        while (i < s.size() && s[i] >= '0' && s[i] <= '9') {
            uint64_t d = static_cast<uint64_t>(s[i] - '0');
            if (v > (UINT64_MAX - d) / 10)
                return false;
            v = v * 10 + d;
            ++i;
        }
        return i > start;
    }
    // A decimal number without exponent, as /proc/loadavg writes them.
    bool number(double &v) noexcept
    {
        uint64_t whole = 0;
        if (!u64(whole))
            return false;
        v = static_cast<double>(whole);
        if (i < s.size() && s[i] == '.') {
            ++i;
            double scale = 0.1;
            while (i < s.size() && s[i] >= '0' && s[i] <= '9') {
                v += (s[i] - '0') * scale;
                scale /= 10;
                ++i;
            }
        }
        return true;
    }
    // Skips one field of non-blank characters; false at the end of the line.
    bool skip_word() noexcept
    {
        blanks();
        size_t start = i;
        while (i < s.size() && s[i] != ' ' && s[i] != '\t' && s[i] != '\n')
            ++i;
        return i > start;
    }
    std::string_view line() noexcept
    {
        size_t start = i;
        while (i < s.size() && s[i] != '\n')
            ++i;
        std::string_view l = s.substr(start, i - start);
        if (i < s.size())
            ++i;
        return l;
    }
};

bool starts(std::string_view line, std::string_view key) noexcept
{
    return line.size() >= key.size() && line.compare(0, key.size(), key) == 0;
}

// "Key:   1234 kB" -> 1234 * 1024 (or 1234 without a unit); false if not a number.
bool key_value(std::string_view line, size_t key_len, uint64_t &v, bool kb)
{
    Scan sc{line, key_len};
    if (!sc.u64(v))
        return false;
    if (kb) {
        if (v > UINT64_MAX / 1024)
            return false;
        v *= 1024;
    }
    return true;
}

} // namespace

Outcome parse_pid_stat(std::string_view text, PidStat &out)
{
    // "pid (comm) state ppid ...": comm may hold blanks and parentheses, so fields are
    // counted from the last ')'.
    size_t close = text.rfind(')');
    if (close == std::string_view::npos)
        return bad("stat", "the command name");
    Scan sc{text, close + 1};
    uint64_t v = 0, utime = 0, stime = 0;
    // fields after ")": 3 state ... 14 utime 15 stime ... 20 num_threads ... 24 rss
    for (int field = 3; field <= 24; ++field) {
        if (field == 3) {
            if (!sc.skip_word())
                return bad("stat", "the state");
            continue;
        }
        sc.blanks();
        bool negative = !sc.end() && sc.s[sc.i] == '-';
        if (negative)
            ++sc.i;
        if (!sc.u64(v))
            return bad("stat", ("field " + std::to_string(field)).c_str());
        if (field == 14)
            utime = v;
        else if (field == 15)
            stime = v;
        else if (field == 20)
            out.threads = static_cast<uint32_t>(v);
        else if (field == 24)
            out.rss_pages = negative ? 0 : v;
    }
    out.ticks = utime + stime;
    return outcome::ok();
}

Outcome parse_pid_status(std::string_view text, PidStatus &out)
{
    Scan sc{text};
    bool vol = false, invol = false;
    out.rss_bytes = 0; // zombies and kernel threads have no VmRSS
    while (!sc.end()) {
        std::string_view l = sc.line();
        if (starts(l, "VmRSS:")) {
            if (!key_value(l, 6, out.rss_bytes, true))
                return bad("status", "VmRSS");
        } else if (starts(l, "voluntary_ctxt_switches:")) {
            if (!key_value(l, 24, out.voluntary, false))
                return bad("status", "voluntary_ctxt_switches");
            vol = true;
        } else if (starts(l, "nonvoluntary_ctxt_switches:")) {
            if (!key_value(l, 27, out.involuntary, false))
                return bad("status", "nonvoluntary_ctxt_switches");
            invol = true;
        }
    }
    if (!vol || !invol)
        return bad("status", "the context switches (no such lines)");
    return outcome::ok();
}

Outcome parse_proc_stat(std::string_view text, CpuTicks &all, std::vector<CpuTicks> &cpus)
{
    Scan sc{text};
    bool seen_all = false;
    cpus.clear();
    while (!sc.end()) {
        std::string_view l = sc.line();
        if (!starts(l, "cpu"))
            continue;
        bool total = l.size() > 3 && (l[3] == ' ' || l[3] == '\t');
        Scan f{l, 3};
        if (!total) {
            uint64_t n = 0;
            if (!f.u64(n)) // "cpuN"
                continue;
        }
        // user nice system idle iowait irq softirq steal (guest time is within user)
        uint64_t v[8] = {};
        int got = 0;
        while (got < 8 && f.u64(v[got]))
            ++got;
        if (got < 4)
            return bad("stat", "a cpu line");
        CpuTicks t;
        for (int k = 0; k < got; ++k)
            t.total += v[k];
        t.busy = t.total - v[3] - v[4];
        if (total) {
            all = t;
            seen_all = true;
        } else {
            cpus.push_back(t);
        }
    }
    if (!seen_all)
        return bad("stat", "the cpu line");
    return outcome::ok();
}

Outcome parse_meminfo(std::string_view text, MemInfo &out)
{
    Scan sc{text};
    bool total = false, available = false;
    uint64_t free = 0;
    out = MemInfo{};
    while (!sc.end()) {
        std::string_view l = sc.line();
        struct {
            const char *key;
            uint64_t *into;
            bool *seen;
        } const keys[] = {{"MemTotal:", &out.total, &total},
                          {"MemAvailable:", &out.available, &available},
                          {"MemFree:", &free, nullptr},
                          {"SwapTotal:", &out.swap_total, nullptr},
                          {"SwapFree:", &out.swap_free, nullptr}};
        for (const auto &k : keys) {
            size_t n = std::strlen(k.key);
            if (!starts(l, k.key))
                continue;
            if (!key_value(l, n, *k.into, true))
                return bad("meminfo", k.key);
            if (k.seen)
                *k.seen = true;
        }
    }
    if (!total)
        return bad("meminfo", "MemTotal");
    if (!available) // kernels before 3.14
        out.available = free;
    return outcome::ok();
}

Outcome parse_net_dev(std::string_view text, std::vector<NetBytes> &out)
{
    Scan sc{text};
    size_t n = 0;
    while (!sc.end()) {
        std::string_view l = sc.line();
        size_t colon = l.find(':');
        if (colon == std::string_view::npos || l.find('|') != std::string_view::npos)
            continue; // the two header lines
        std::string_view name = l.substr(0, colon);
        while (!name.empty() && (name.front() == ' ' || name.front() == '\t'))
            name.remove_prefix(1);
        if (name.empty())
            return bad("net/dev", "an interface name");
        // rx: bytes packets errs drop fifo frame compressed multicast; tx: bytes ...
        Scan f{l, colon + 1};
        uint64_t v[9] = {};
        for (uint64_t &x : v)
            if (!f.u64(x))
                return bad("net/dev", "the byte counters");
        if (n == out.size())
            out.emplace_back();
        NetBytes &e = out[n++];
        e.interface.assign(name.data(), name.size());
        e.rx = v[0];
        e.tx = v[8];
    }
    out.resize(n);
    return outcome::ok();
}

Outcome parse_loadavg(std::string_view text, LoadAvg &out)
{
    Scan sc{text};
    if (!sc.number(out.one) || !sc.number(out.five) || !sc.number(out.fifteen))
        return bad("loadavg", "the load averages");
    return outcome::ok();
}

// ---- Sampler -----------------------------------------------------------------------------

Sampler::Sampler(std::string root, long hz)
    : root_(std::move(root)), hz_(static_cast<double>(hz > 0 ? hz : ::sysconf(_SC_CLK_TCK))),
      page_(static_cast<uint64_t>(::sysconf(_SC_PAGESIZE)))
{
    buf_.resize(16384);
    struct statfs fs;
    proc_fs_ = ::statfs(root_.c_str(), &fs) == 0 && fs.f_type == PROC_SUPER_MAGIC;
}

Outcome Sampler::read(const char *what, pid_t pid)
{
    path_.assign(root_);
    if (pid > 0) {
        path_ += '/';
        path_ += std::to_string(pid);
    }
    path_ += '/';
    path_ += what;
    int fd = ::open(path_.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0)
        return outcome::error(Err::os_error, path_ + ": " + std::strerror(errno));
    size_t used = 0;
    for (;;) {
        if (used == buf_.size())
            buf_.resize(buf_.size() * 2);
        ssize_t n = ::read(fd, &buf_[used], buf_.size() - used);
        if (n < 0 && errno == EINTR)
            continue;
        if (n < 0) {
            int e = errno;
            ::close(fd);
            return outcome::error(Err::os_error, path_ + ": " + std::strerror(e));
        }
        if (n == 0)
            break;
        used += static_cast<size_t>(n);
    }
    ::close(fd);
    text_ = std::string_view(buf_.data(), used);
    return outcome::ok();
}

uint32_t Sampler::count_fds(pid_t pid)
{
    path_.assign(root_);
    path_ += '/';
    path_ += std::to_string(pid);
    path_ += "/fd";
    // Linux >= 6.2 gives the count as the size of /proc/PID/fd: one stat instead of a listing
    // (0 on older kernels, and 0 open descriptors, which the listing then finds).
    struct stat st;
    if (proc_fs_ && ::stat(path_.c_str(), &st) == 0 && st.st_size > 0)
        return static_cast<uint32_t>(st.st_size);
    DIR *d = ::opendir(path_.c_str());
    if (!d)
        return 0;
    uint32_t n = 0;
    while (dirent *e = ::readdir(d))
        if (e->d_name[0] != '.')
            ++n;
    ::closedir(d);
    return n;
}

namespace {

double percent(uint64_t busy, uint64_t prev_busy, uint64_t total, uint64_t prev_total)
{
    if (total <= prev_total || busy < prev_busy)
        return 0;
    double d = static_cast<double>(busy - prev_busy) / static_cast<double>(total - prev_total);
    return d > 1 ? 100 : 100 * d;
}

} // namespace

Outcome Sampler::sample_host(double now, wire::EvResources &out)
{
    LoadAvg load;
    MemInfo mem;
    Outcome o = read("loadavg", 0);
    if (!o.failed())
        o = parse_loadavg(text_, load);
    if (!o.failed())
        o = read("meminfo", 0);
    if (!o.failed())
        o = parse_meminfo(text_, mem);
    if (!o.failed())
        o = read("stat", 0);
    if (!o.failed())
        o = parse_proc_stat(text_, all_, cpus_);
    if (!o.failed())
        o = read("net/dev", 0);
    if (!o.failed())
        o = parse_net_dev(text_, net_);
    if (o.failed())
        return o;
    out.load1 = load.one;
    out.load5 = load.five;
    out.load15 = load.fifteen;
    out.mem_total = mem.total;
    out.mem_available = mem.available;
    out.swap_total = mem.swap_total;
    out.swap_free = mem.swap_free;
    bool first = prev_time_ < 0;
    out.cpu = first ? 0 : percent(all_.busy, prev_all_.busy, all_.total, prev_all_.total);
    out.cpus.resize(cpus_.size());
    for (size_t k = 0; k < cpus_.size(); ++k)
        out.cpus[k] =
            first || k >= prev_cpus_.size()
                ? 0
                : percent(cpus_[k].busy, prev_cpus_[k].busy, cpus_[k].total, prev_cpus_[k].total);
    double dt = first ? 0 : now - prev_time_;
    out.nets.resize(net_.size());
    for (size_t k = 0; k < net_.size(); ++k) {
        wire::NetRate &r = out.nets[k];
        r.interface = net_[k].interface;
        r.rx = r.tx = 0;
        if (dt <= 0)
            continue;
        for (const NetBytes &p : prev_net_) // interfaces come and go: match by name
            if (p.interface == net_[k].interface) {
                r.rx = net_[k].rx >= p.rx ? static_cast<double>(net_[k].rx - p.rx) / dt : 0;
                r.tx = net_[k].tx >= p.tx ? static_cast<double>(net_[k].tx - p.tx) / dt : 0;
                break;
            }
    }
    prev_all_ = all_;
    std::swap(prev_cpus_, cpus_);
    std::swap(prev_net_, net_);
    prev_time_ = now;
    return outcome::ok();
}

Outcome Sampler::sample_process(pid_t pid, double now, wire::ProcessResources &out)
{
    PidStat st;
    PidStatus status;
    Outcome o = read("stat", pid);
    if (!o.failed())
        o = parse_pid_stat(text_, st);
    if (!o.failed())
        o = read("status", pid);
    if (!o.failed())
        o = parse_pid_status(text_, status);
    if (o.failed())
        return o;
    out.pid = static_cast<uint32_t>(pid);
    out.threads = st.threads;
    out.rss = status.rss_bytes ? status.rss_bytes : st.rss_pages * page_;
    out.voluntary = status.voluntary;
    out.involuntary = status.involuntary;
    out.fds = count_fds(pid);
    auto [it, fresh] = previous_.try_emplace(pid, Previous{st.ticks, now, -1});
    Previous &prev = it->second;
    double dt = now - prev.time;
    if (!fresh && dt < kMinPeriod / 2) { // sampled again in the same round (two connections)
        out.cpu = prev.cpu;
        return outcome::ok();
    }
    if (fresh || st.ticks < prev.ticks)
        out.cpu = -1;
    else
        out.cpu = 100.0 * static_cast<double>(st.ticks - prev.ticks) / hz_ / dt;
    prev = Previous{st.ticks, now, out.cpu};
    return outcome::ok();
}

void Sampler::forget_older(double before)
{
    for (auto it = previous_.begin(); it != previous_.end();)
        if (it->second.time < before)
            it = previous_.erase(it);
        else
            ++it;
}

} // namespace lnd::res
