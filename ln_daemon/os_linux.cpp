// LinuxOs (os_linux.hpp).  The daemon runs Forwarder threads besides its poll loop, so the
// forked keeper and child only make system calls (no allocation, no locks another thread may
// have held at the fork): all they need is prepared before the fork.  Every descriptor the
// daemon opens is O_CLOEXEC, and the keeper closes all it does not need.
#include "os_linux.hpp"

#include <algorithm>
#include <array>
#include <cerrno>
#include <climits>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <dirent.h>
#include <fcntl.h>
#include <memory>
#include <poll.h>
#include <sched.h>
#include <sys/ioctl.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/signalfd.h>
#include <sys/wait.h>
#include <termios.h>
#include <unistd.h>
#include <unordered_map>

extern char **environ;

namespace lnd {

namespace {

Outcome failed(std::string text)
{
    return outcome::error(proto::Err::spawn_failed, std::move(text));
}

constexpr int kKeeperSweepMs = 100; // between the keeper's own SIGKILL sweeps

double clock_seconds(clockid_t id) noexcept
{
    struct timespec ts;
    ::clock_gettime(id, &ts);
    return static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec) * 1e-9;
}

bool set_nonblocking(int fd) noexcept
{
    int flags = ::fcntl(fd, F_GETFL);
    return flags >= 0 && ::fcntl(fd, F_SETFL, flags | O_NONBLOCK) == 0;
}

bool make_pipe(UniqueFd &read_end, UniqueFd &write_end) noexcept
{
    int fds[2];
    if (::pipe2(fds, O_CLOEXEC) != 0)
        return false;
    read_end.reset(fds[0]);
    write_end.reset(fds[1]);
    return true;
}

// Opens a pty pair: the master for the daemon, the slave for the child.  No echo and no
// CR before LF, so the output reads as the program wrote it.
Outcome open_pty(UniqueFd &master, UniqueFd &slave)
{
    master.reset(::open("/dev/ptmx", O_RDWR | O_NOCTTY | O_CLOEXEC));
    char name[64];
    if (!master || ::grantpt(master.get()) != 0 || ::unlockpt(master.get()) != 0 ||
        ::ptsname_r(master.get(), name, sizeof name) != 0) {
        return failed(std::string("cannot open a pseudo-terminal: ") + std::strerror(errno));
    }
    slave.reset(::open(name, O_RDWR | O_NOCTTY | O_CLOEXEC));
    if (!slave)
        return failed(std::string("cannot open pseudo-terminal ") + name + ": " +
                      std::strerror(errno));
    struct termios tio;
    if (::tcgetattr(slave.get(), &tio) == 0) {
        tio.c_oflag &= ~static_cast<tcflag_t>(ONLCR);
        tio.c_lflag &= ~static_cast<tcflag_t>(ECHO | ECHONL);
        ::tcsetattr(slave.get(), TCSANOW, &tio);
    }
    struct winsize ws = {};
    ws.ws_row = 50;
    ws.ws_col = 160;
    ::ioctl(slave.get(), TIOCSWINSZ, &ws);
    return outcome::ok();
}

// Closes every descriptor from 3 up except those in `keep`.
void close_all_except(std::array<int, 4> keep) noexcept
{
    std::sort(keep.begin(), keep.end());
    unsigned lo = 3;
    for (int fd : keep) {
        if (fd < static_cast<int>(lo))
            continue;
        if (static_cast<unsigned>(fd) > lo)
            ::close_range(lo, static_cast<unsigned>(fd) - 1, 0);
        lo = static_cast<unsigned>(fd) + 1;
    }
    ::close_range(lo, ~0u, 0);
}

struct ChildStatus {
    int32_t stage;
    int32_t index;
    int32_t err;
};

[[noreturn]] void child_fail(int status_fd, Stage stage, int index) noexcept
{
    ChildStatus st{static_cast<int32_t>(stage), index, errno};
    ssize_t rc = ::write(status_fd, &st, sizeof st);
    (void)rc;
    ::_exit(127);
}

// Everything the child needs, prepared by the daemon before the fork.
struct Prepared {
    const LaunchSpec &spec;
    std::vector<char *> argv;
    std::vector<char *> envp;
    struct rlimit nofile; // RLIMIT_NOFILE as the daemon found it
    int stdin_fd = -1;    // pipes: /dev/null
    int out_fd = -1;      // pipe write end, or the pty slave
    int err_fd = -1;      // pipe write end, or the pty slave
    bool pty = false;
};

// The supervised process, between fork and exec.  Reports the first failing step through
// `status_fd` (close-on-exec, so a successful exec just closes it).
[[noreturn]] void child_main(const Prepared &p, int status_fd) noexcept
{
    if (::setsid() < 0)
        child_fail(status_fd, Stage::setup, 0);
    if (p.pty && ::ioctl(p.out_fd, TIOCSCTTY, 0) != 0)
        child_fail(status_fd, Stage::setup, 0);
    if (::dup2(p.stdin_fd, 0) < 0 || ::dup2(p.out_fd, 1) < 0 || ::dup2(p.err_fd, 2) < 0)
        child_fail(status_fd, Stage::setup, 0);
    if (::chdir(p.spec.cwd.c_str()) != 0)
        child_fail(status_fd, Stage::chdir, 0);
    // The daemon raised its own descriptor limit; the process gets the one it started with.
    ::setrlimit(RLIMIT_NOFILE, &p.nofile);
    for (size_t i = 0; i < p.spec.rlimits.size(); ++i) {
        const Rlimit &r = p.spec.rlimits[i];
        struct rlimit rl = {r.soft, r.hard};
        if (::setrlimit(r.resource, &rl) != 0)
            child_fail(status_fd, Stage::rlimit, static_cast<int>(i));
    }
    struct sched_param sp = {};
    bool realtime = p.spec.policy == SCHED_FIFO || p.spec.policy == SCHED_RR;
    sp.sched_priority = realtime ? p.spec.priority : 0;
    if (::sched_setscheduler(0, p.spec.policy, &sp) != 0)
        child_fail(status_fd, Stage::scheduler, 0);
    if (!realtime && ::setpriority(PRIO_PROCESS, 0, p.spec.priority) != 0)
        child_fail(status_fd, Stage::nice, 0);
    if (!p.spec.affinity.empty()) {
        cpu_set_t set;
        CPU_ZERO(&set);
        for (int cpu : p.spec.affinity)
            CPU_SET(cpu, &set);
        if (::sched_setaffinity(0, sizeof set, &set) != 0)
            child_fail(status_fd, Stage::affinity, 0);
    }
    // Signal dispositions and the mask survive exec: give the program the defaults.
    struct sigaction sa = {};
    sa.sa_handler = SIG_DFL;
    for (int sig = 1; sig < NSIG; ++sig)
        ::sigaction(sig, &sa, nullptr);
    sigset_t none;
    sigemptyset(&none);
    ::sigprocmask(SIG_SETMASK, &none, nullptr);
    environ = const_cast<char **>(p.envp.data()); // execvp searches this PATH
    ::execvp(p.argv[0], p.argv.data());
    child_fail(status_fd, Stage::exec, 0);
}

void write_report(int fd, KeeperReport r) noexcept
{
    ssize_t rc;
    do
        rc = ::write(fd, &r, sizeof r);
    while (rc < 0 && errno == EINTR);
}

// Parent and process group of `pid` from /proc/PID/stat, with nothing but system calls and
// the stack (the keeper uses it too).  "PID (COMM) STATE PPID PGRP ...": COMM may hold
// anything, so parsing starts after the last ')'.
bool read_proc_stat(long pid, pid_t &ppid, pid_t &pgrp) noexcept
{
    char path[32] = "/proc/";
    char digits[24];
    int nd = 0;
    for (long v = pid; v > 0 && nd < 20; v /= 10)
        digits[nd++] = static_cast<char>('0' + v % 10);
    size_t at = 6;
    while (nd > 0)
        path[at++] = digits[--nd];
    std::memcpy(path + at, "/stat", 6);
    int fd = ::open(path, O_RDONLY | O_CLOEXEC);
    if (fd < 0)
        return false;
    char buf[1024];
    ssize_t n = ::read(fd, buf, sizeof buf - 1);
    ::close(fd);
    if (n <= 0)
        return false;
    buf[n] = 0;
    const char *q = std::strrchr(buf, ')');
    if (!q || q[1] != ' ' || !q[2] || q[3] != ' ')
        return false;
    q += 4; // past ") S "
    long fields[2];
    for (long &f : fields) {
        bool neg = *q == '-';
        q += neg;
        if (*q < '0' || *q > '9')
            return false;
        f = 0;
        while (*q >= '0' && *q <= '9')
            f = f * 10 + (*q++ - '0');
        f = neg ? -f : f;
        if (*q == ' ')
            ++q;
    }
    ppid = static_cast<pid_t>(fields[0]);
    pgrp = static_cast<pid_t>(fields[1]);
    return true;
}

// The keeper's own sweep: sends `sig` to each of its children outside process group `skip`
// (0: none).  Being a child subreaper, it inherits every orphan of the tree, so repeated
// sweeps (each reaping in between) reach the whole tree.  System calls and the stack only.
void signal_children(int sig, pid_t skip) noexcept
{
    int dir = ::open("/proc", O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (dir < 0)
        return;
    pid_t self = ::getpid();
    alignas(8) char buf[4096];
    ssize_t n;
    while ((n = ::getdents64(dir, buf, sizeof buf)) > 0) {
        for (ssize_t off = 0; off < n;) {
            const auto *d = reinterpret_cast<const struct dirent64 *>(buf + off);
            off += d->d_reclen;
            long pid = 0;
            const char *c = d->d_name;
            for (; *c >= '0' && *c <= '9' && pid < INT_MAX / 10; ++c)
                pid = pid * 10 + (*c - '0');
            pid_t ppid, pgrp;
            if (*c || pid <= 0 || !read_proc_stat(pid, ppid, pgrp))
                continue;
            if (ppid == self && (skip == 0 || pgrp != skip))
                ::kill(static_cast<pid_t>(pid), sig);
        }
    }
    ::close(dir);
}

// The keeper: a child subreaper between the daemon and the supervised process, so that
// every orphan of the process tree is re-parented to it and nothing escapes.  It starts
// the child, reports start (or setup failure) and the child's exit on `report_fd`, reaps
// everything, and exits when it has no children left: the tree is empty.  If the daemon
// goes away without ending the tree (SIGKILL, a crash), the report pipe loses its reader;
// nobody could stop or even see the tree any more, so the keeper ends it as STOP would:
// the term signal, SIGKILL after the term timeout.
[[noreturn]] void keeper_main(const Prepared &p, int report_fd) noexcept
{
    ::setpgid(0, 0); // out of the daemon's group: a Ctrl-C there is not for us
    sigset_t chld;
    sigemptyset(&chld);
    sigaddset(&chld, SIGCHLD);
    ::sigprocmask(SIG_SETMASK, &chld, nullptr); // SIGCHLD only through the signalfd
    for (int sig : {SIGINT, SIGTERM, SIGHUP, SIGQUIT, SIGPIPE, SIGUSR1, SIGUSR2})
        ::signal(sig, SIG_IGN);
    ::prctl(PR_SET_CHILD_SUBREAPER, 1);
    ::prctl(PR_SET_NAME, "ln_daemon-keep");
    {
        UniqueFd null_fd(::open("/dev/null", O_RDWR));
        for (int target = 0; null_fd && target <= 2; ++target)
            ::dup2(null_fd.get(), target);
        if (null_fd.get() <= 2)
            null_fd.release(); // it is one of the standard streams now
    }
    close_all_except({report_fd, p.stdin_fd, p.out_fd, p.err_fd});

    UniqueFd status_r, status_w;
    UniqueFd sigfd(::signalfd(-1, &chld, SFD_NONBLOCK | SFD_CLOEXEC));
    if (!sigfd || !make_pipe(status_r, status_w)) {
        write_report(report_fd,
                     {KeeperReport::failed, static_cast<int32_t>(Stage::setup), 0, errno});
        ::_exit(1);
    }
    pid_t child = ::fork();
    if (child == 0) {
        status_r.reset();
        child_main(p, status_w.get());
    }
    int fork_errno = errno;
    status_w.reset();
    for (int fd : {p.stdin_fd, p.out_fd, p.err_fd})
        if (fd >= 0)
            ::close(fd); // the tree's ends only: the keeper must not keep a stream open
    if (child < 0) {
        write_report(report_fd,
                     {KeeperReport::failed, static_cast<int32_t>(Stage::setup), 0, fork_errno});
        ::_exit(1);
    }
    ChildStatus st;
    ssize_t n;
    do
        n = ::read(status_r.get(), &st, sizeof st);
    while (n < 0 && errno == EINTR);
    status_r.reset();
    if (n == static_cast<ssize_t>(sizeof st))
        write_report(report_fd, {KeeperReport::failed, st.stage, st.index, st.err});
    else
        write_report(report_fd, {KeeperReport::started, child, 0, 0});

    bool orphaned = false;     // the daemon is gone: the keeper ends the tree itself
    bool child_reaped = false; // then its pid may be reused: no more signals to its group
    double kill_at = 0;        // monotonic: SIGKILL sweeps from then on
    for (;;) {
        for (;;) {
            int status;
            pid_t pid = ::waitpid(-1, &status, WNOHANG);
            if (pid > 0) {
                if (pid == child) {
                    child_reaped = true;
                    write_report(report_fd, {KeeperReport::main_exit, status, 0, 0});
                }
                continue;
            }
            if (pid < 0 && errno == EINTR)
                continue;
            if (pid < 0)
                ::_exit(0); // ECHILD: the tree is empty
            break;          // children left
        }
        int timeout = -1;
        if (orphaned) {
            double left = kill_at - clock_seconds(CLOCK_MONOTONIC);
            if (left <= 0) {
                if (!child_reaped)
                    ::kill(-child, SIGKILL);
                signal_children(SIGKILL, 0);
                timeout = kKeeperSweepMs;
            } else {
                timeout = left > 60 ? 60000 : static_cast<int>(std::ceil(left * 1000));
            }
        }
        struct pollfd fds[2] = {{sigfd.get(), POLLIN, 0}, {orphaned ? -1 : report_fd, 0, 0}};
        if (::poll(fds, 2, timeout) < 0 && errno != EINTR)
            ::_exit(1);
        if (fds[0].revents) {
            struct signalfd_siginfo si;
            while (::read(sigfd.get(), &si, sizeof si) > 0) {
            }
        }
        if (!orphaned && (fds[1].revents & (POLLERR | POLLHUP))) {
            // Nobody reads the reports any more.
            orphaned = true;
            if (!child_reaped)
                ::kill(-child, p.spec.term_signal);
            // Members that left the group (all of them once the group is gone).
            signal_children(p.spec.term_signal, child_reaped ? 0 : child);
            kill_at = clock_seconds(CLOCK_MONOTONIC) + p.spec.term_timeout;
        }
    }
}

struct DirCloser {
    void operator()(DIR *d) const noexcept { ::closedir(d); }
};

struct ProcEntry {
    pid_t ppid;
    pid_t pgrp;
};

// pid -> (parent, process group) of every process, from /proc/PID/stat.
std::unordered_map<pid_t, ProcEntry> scan_proc()
{
    std::unordered_map<pid_t, ProcEntry> table;
    std::unique_ptr<DIR, DirCloser> dir(::opendir("/proc"));
    if (!dir)
        return table;
    while (struct dirent *e = ::readdir(dir.get())) {
        char *end;
        long pid = std::strtol(e->d_name, &end, 10);
        if (*end || pid <= 0)
            continue;
        pid_t ppid, pgrp;
        if (!read_proc_stat(pid, ppid, pgrp))
            continue;
        table[static_cast<pid_t>(pid)] = {ppid, pgrp};
    }
    return table;
}

} // namespace

LinuxOs::LinuxOs() noexcept
{
    // Each running process holds two or three descriptors in the daemon: raise the soft
    // limit as far as allowed (children get the original one back).
    if (::getrlimit(RLIMIT_NOFILE, &nofile_) != 0)
        return;
    struct rlimit raised = nofile_;
    raised.rlim_cur =
        raised.rlim_max == RLIM_INFINITY || raised.rlim_max > 65536 ? 65536 : raised.rlim_max;
    if (raised.rlim_cur > nofile_.rlim_cur)
        ::setrlimit(RLIMIT_NOFILE, &raised);
}

double LinuxOs::monotonic() noexcept { return clock_seconds(CLOCK_MONOTONIC); }

double LinuxOs::wall() noexcept { return clock_seconds(CLOCK_REALTIME); }

Outcome LinuxOs::launch(const LaunchSpec &spec, Launched &out)
{
    Prepared p{spec, {}, {}, nofile_};
    for (const auto &a : spec.argv)
        p.argv.push_back(const_cast<char *>(a.c_str()));
    p.argv.push_back(nullptr);
    for (const auto &e : spec.env)
        p.envp.push_back(const_cast<char *>(e.c_str()));
    p.envp.push_back(nullptr);

    UniqueFd report_r, report_w, stdin_null, out_r, out_w, err_r, err_w, master, slave;
    if (!make_pipe(report_r, report_w))
        return failed(std::string("cannot create a pipe: ") + std::strerror(errno));
    if (spec.use_pty) {
        if (Outcome o = open_pty(master, slave); o.failed())
            return o;
        p.pty = true;
        p.stdin_fd = p.out_fd = p.err_fd = slave.get();
    } else {
        stdin_null.reset(::open("/dev/null", O_RDONLY | O_CLOEXEC));
        if (!stdin_null || !make_pipe(out_r, out_w) || !make_pipe(err_r, err_w))
            return failed(std::string("cannot create the output pipes: ") + std::strerror(errno));
        p.stdin_fd = stdin_null.get();
        p.out_fd = out_w.get();
        p.err_fd = err_w.get();
    }
    for (const UniqueFd *fd : {&report_r, &out_r, &err_r, &master})
        if (*fd)
            set_nonblocking(fd->get());

    pid_t keeper = ::fork();
    if (keeper < 0)
        return failed(std::string("cannot fork: ") + std::strerror(errno));
    if (keeper == 0)
        keeper_main(p, report_w.get());
    out.keeper = keeper;
    out.report = std::move(report_r);
    if (spec.use_pty) {
        out.out = std::move(master);
        out.slave = std::move(slave); // until the child has opened it: see Process
    } else {
        out.out = std::move(out_r);
        out.err = std::move(err_r);
    }
    return outcome::ok(); // the write ends close here: only the keeper and the tree hold them
}

int LinuxOs::kill(pid_t pid, int sig) noexcept { return ::kill(pid, sig) == 0 ? 0 : -errno; }

int LinuxOs::kill_tree(pid_t keeper, int sig, pid_t skip_group) noexcept
{
    std::unordered_map<pid_t, ProcEntry> table;
    try {
        table = scan_proc();
    } catch (...) { // out of memory: nothing sensible left to do but report nothing found
        return 0;
    }
    std::unordered_multimap<pid_t, pid_t> children;
    for (const auto &[pid, entry] : table)
        children.emplace(entry.ppid, pid);
    std::vector<pid_t> todo{keeper};
    int found = 0;
    while (!todo.empty()) {
        pid_t parent = todo.back();
        todo.pop_back();
        auto range = children.equal_range(parent);
        for (auto it = range.first; it != range.second; ++it) {
            pid_t pid = it->second;
            todo.push_back(pid);
            ++found;
            if (skip_group == 0 || table[pid].pgrp != skip_group)
                ::kill(pid, sig);
        }
    }
    return found;
}

bool LinuxOs::reap(pid_t &pid, int &status) noexcept
{
    pid_t r;
    do
        r = ::waitpid(-1, &status, WNOHANG);
    while (r < 0 && errno == EINTR);
    if (r <= 0)
        return false;
    pid = r;
    return true;
}

} // namespace lnd
