// Implementation of the daemon log (log.hpp): a file descriptor owned here, formatting
// into a stack buffer so logging never allocates or fails loudly.
#include "log.hpp"

#include <cerrno>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <fcntl.h>
#include <sys/time.h>
#include <unistd.h>

#include "fd.hpp"
#include "outcome.hpp"

namespace lnd {

namespace {
UniqueFd g_log_fd; // empty: stderr
} // namespace

Outcome log_open(const std::string &path)
{
    int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC | O_NOCTTY, 0640);
    if (fd < 0)
        return outcome::error(proto::Err::os_error,
                              "cannot open log file '" + path + "': " + std::strerror(errno));
    g_log_fd.reset(fd);
    return outcome::ok();
}

void log_discard() noexcept { g_log_fd.reset(::open("/dev/null", O_WRONLY | O_CLOEXEC)); }

void logf(const char *fmt, ...) noexcept
{
    char line[2048];
    struct timeval tv;
    ::gettimeofday(&tv, nullptr);
    struct tm tm;
    ::localtime_r(&tv.tv_sec, &tm);
    size_t n = std::strftime(line, sizeof line, "%Y-%m-%d %H:%M:%S", &tm);
    int m = std::snprintf(line + n, sizeof line - n,
                          ".%03ld ln_daemon[%ld]: ", static_cast<long>(tv.tv_usec / 1000),
                          static_cast<long>(::getpid()));
    if (m > 0)
        n += static_cast<size_t>(m);
    va_list ap;
    va_start(ap, fmt);
    m = std::vsnprintf(line + n, sizeof line - n - 1, fmt, ap);
    va_end(ap);
    if (m > 0)
        n += static_cast<size_t>(m) < sizeof line - n - 1 ? static_cast<size_t>(m)
                                                          : sizeof line - n - 2;
    line[n++] = '\n';
    int fd = g_log_fd ? g_log_fd.get() : 2;
    ssize_t rc = ::write(fd, line, n);
    (void)rc; // nowhere left to report a failing log
}

} // namespace lnd
