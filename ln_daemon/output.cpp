// Line splitting, the bounded line list and log rotation (output.hpp).  A failing log file
// is reported once in the daemon log and then closed, never stopping the process.
#include "output.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fcntl.h>
#include <sys/stat.h>
#include <sys/uio.h>
#include <unistd.h>

#include "log.hpp"

namespace lnd {

void LineSplitter::feed(const char *data, size_t n, double now, const Emit &emit)
{
    while (n > 0) {
        if (partial_.empty())
            since_ = now;
        const char *nl = static_cast<const char *>(std::memchr(data, '\n', n));
        size_t take = nl ? static_cast<size_t>(nl - data) : n;
        size_t room = kMaxLineBytes - partial_.size();
        if (take > room || (!nl && take == room)) { // too long: cut it here
            partial_.append(data, room);
            data += room;
            n -= room;
            emit(std::move(partial_));
            partial_.clear();
            continue;
        }
        partial_.append(data, take);
        data += take;
        n -= take;
        if (!nl)
            break;
        ++data; // the newline
        --n;
        if (!partial_.empty() && partial_.back() == '\r')
            partial_.pop_back();
        emit(std::move(partial_));
        partial_.clear();
    }
}

void LineSplitter::flush(const Emit &emit)
{
    if (partial_.empty())
        return;
    if (partial_.back() == '\r')
        partial_.pop_back();
    emit(std::move(partial_));
    partial_.clear();
}

void LineBuffer::add(const Line &line)
{
    ++total_;
    if (capacity_ == 0)
        return;
    while (!lines_.empty() &&
           (lines_.size() >= capacity_ || bytes_ + line.text.size() > kMaxKeptBytes)) {
        bytes_ -= lines_.front().text.size();
        lines_.pop_front();
    }
    lines_.push_back(line);
    bytes_ += line.text.size();
}

namespace {

// Opens (creating) an output log for writing.  Only a regular file will do: the daemon's one
// poll loop must not block in open() or write() of a FIFO or a terminal, and the rotation
// renames the file, which must never happen to a device such as /dev/null.  O_NONBLOCK makes
// the open of a FIFO return at once, to be refused like anything else that is not regular.
Outcome open_regular(const std::string &path, int flags, uint64_t &size, UniqueFd &out)
{
    auto failed = [](std::string text) {
        return outcome::error(proto::Err::spawn_failed, std::move(text));
    };
    UniqueFd fd(
        ::open(path.c_str(), O_WRONLY | O_CREAT | O_CLOEXEC | O_NOCTTY | O_NONBLOCK | flags, 0644));
    struct stat st;
    if (!fd && errno == ENXIO) { // a FIFO without a reader, or a socket
        return failed("output log '" + path + "' is not a regular file");
    }
    if (!fd || ::fstat(fd.get(), &st) != 0)
        return failed("cannot open output log '" + path + "': " + std::strerror(errno));
    if (!S_ISREG(st.st_mode))
        return failed("output log '" + path + "' is not a regular file");
    size = static_cast<uint64_t>(st.st_size);
    out = std::move(fd);
    return outcome::ok();
}

} // namespace

Outcome RotatingLog::open(const std::string &path, uint64_t limit, uint32_t keep)
{
    path_ = path;
    limit_ = limit;
    keep_ = keep;
    uint64_t size = 0;
    Outcome o = open_regular(path, O_APPEND, size, fd_);
    size_ = size;
    return o;
}

bool RotatingLog::rotate() noexcept
{
    fd_.reset();
    // PATH.(keep-1) -> PATH.keep, ..., PATH -> PATH.1; the rename over PATH.keep drops the
    // oldest file.
    for (uint32_t i = keep_; i >= 1; --i) {
        std::string from = i == 1 ? path_ : path_ + "." + std::to_string(i - 1);
        std::string to = path_ + "." + std::to_string(i);
        if (::rename(from.c_str(), to.c_str()) != 0 && errno != ENOENT)
            logf("output log %s: cannot rename to %s: %s", from.c_str(), to.c_str(),
                 std::strerror(errno));
    }
    uint64_t size;
    if (Outcome o = open_regular(path_, O_TRUNC | O_APPEND, size, fd_); o.failed()) {
        logf("%s after rotation, logging stops", o.text.c_str());
        return false;
    }
    size_ = 0;
    return true;
}

void RotatingLog::write_line(std::string_view text) noexcept
{
    if (!fd_)
        return;
    size_t len = text.size() + 1;
    if (limit_ && size_ > 0 && size_ + len > limit_ && !rotate())
        return;
    struct iovec iov[2] = {{const_cast<char *>(text.data()), text.size()},
                           {const_cast<char *>("\n"), 1}};
    ssize_t n = ::writev(fd_.get(), iov, 2);
    if (n < 0) {
        logf("output log %s: write failed, logging stops: %s", path_.c_str(), std::strerror(errno));
        fd_.reset();
        return;
    }
    size_ += static_cast<uint64_t>(n);
}

} // namespace lnd
