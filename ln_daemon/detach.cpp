// The launcher/daemon split at start-up (detach.hpp).  The verdict on the pipe is "ok PORT"
// (the data port) or "error TEXT"; EOF without either means the daemon died.
#include "detach.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fcntl.h>
#include <unistd.h>

#include "log.hpp"

namespace lnd {

namespace {

void report(int fd, const std::string &verdict) noexcept
{
    const char *p = verdict.data();
    size_t left = verdict.size();
    while (left > 0) {
        ssize_t n = ::write(fd, p, left);
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0)
            return;
        p += n;
        left -= static_cast<size_t>(n);
    }
}

std::string read_verdict(int fd)
{
    std::string text;
    char buf[512];
    for (;;) {
        ssize_t n = ::read(fd, buf, sizeof buf);
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0)
            return text;
        text.append(buf, static_cast<size_t>(n));
    }
}

void redirect_stdio_to_null()
{
    UniqueFd null_fd(::open("/dev/null", O_RDWR | O_CLOEXEC));
    for (int target = 0; null_fd && target <= 2; ++target)
        ::dup2(null_fd.get(), target); // dup2 clears close-on-exec on the copies
    if (null_fd.get() <= 2)
        null_fd.release(); // it is one of the standard streams now
}

Outcome cannot(const char *what)
{
    return outcome::error(proto::Err::os_error, std::string(what) + std::strerror(errno));
}

} // namespace

int fail(const std::string &text)
{
    std::fprintf(stderr, "ln_daemon: error: %s\n", text.c_str());
    return 1;
}

Outcome Detacher::detach(const std::string &where, int &launcher_status)
{
    launcher_status = -1;
    int fds[2];
    if (::pipe2(fds, O_CLOEXEC) != 0)
        return cannot("cannot create a pipe: ");
    UniqueFd verdict_r(fds[0]), verdict_w(fds[1]);
    std::fflush(stdout);
    pid_t child = ::fork();
    if (child < 0)
        return cannot("cannot fork: ");
    if (child > 0) {
        verdict_w.reset();
        std::string text = read_verdict(verdict_r.get());
        if (text.rfind("ok ", 0) == 0) {
            std::printf("ln_daemon: listening on %s (pid %d), data port %s\n", where.c_str(),
                        static_cast<int>(child), text.c_str() + 3);
            launcher_status = 0;
        } else if (text.rfind("error ", 0) == 0) {
            launcher_status = lnd::fail(text.substr(6));
        } else {
            launcher_status = lnd::fail("the daemon ended during start-up");
        }
        return outcome::ok();
    }
    verdict_r.reset();
    verdict_ = std::move(verdict_w);
    ::setsid();
    if (::chdir("/") != 0)
        return cannot("cannot change to /: ");
    return outcome::ok();
}

int Detacher::fail(const std::string &text)
{
    if (!verdict_)
        return lnd::fail(text);
    report(verdict_.get(), "error " + text);
    return 1;
}

void Detacher::started(const std::string &where, unsigned data_port, bool keep_log)
{
    if (verdict_) {
        report(verdict_.get(), "ok " + std::to_string(data_port));
        verdict_.reset();
        redirect_stdio_to_null();
        if (!keep_log)
            log_discard();
    } else {
        std::printf("ln_daemon: listening on %s (pid %d), data port %u\n", where.c_str(),
                    static_cast<int>(::getpid()), data_port);
        std::fflush(stdout);
    }
}

} // namespace lnd
