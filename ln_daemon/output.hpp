// Output capture pieces: splitting a byte stream into lines (with a flush of partial lines
// after a short time), the bounded list of recent lines, and the rotating log file.
#pragma once

#include <cstdint>
#include <deque>
#include <functional>
#include <string>
#include <string_view>

#include "fd.hpp"
#include "outcome.hpp"
#include "protocol.hpp"

namespace lnd {

struct Line {
    double time; // wall clock
    proto::Stream stream;
    std::string text; // without the newline (and without a trailing CR)
};

constexpr size_t kMaxLineBytes = 16384;     // longer lines are cut into pieces
constexpr double kPartialFlushDelay = 0.1;  // seconds a partial line waits for its end
constexpr size_t kMaxKeptBytes = 64u << 20; // text kept in memory per process, at most

// Cuts one stream's bytes into lines.  A partial line is held back until its newline, until
// it reaches kMaxLineBytes, or until flush() (after kPartialFlushDelay, or at the end).
class LineSplitter {
public:
    using Emit = std::function<void(std::string &&text)>;
    void feed(const char *data, size_t n, double now, const Emit &emit);
    void flush(const Emit &emit);
    bool pending() const noexcept { return !partial_.empty(); }
    // Monotonic time at which the partial line is due to be flushed.
    double flush_due() const noexcept { return since_ + kPartialFlushDelay; }

private:
    std::string partial_;
    double since_ = 0; // monotonic time the partial line began
};

// The last `capacity` lines of a process, at most kMaxKeptBytes of text (a process writing
// long lines must not make the daemon hold up to capacity x kMaxLineBytes), and how many
// lines there were in all.
class LineBuffer {
public:
    explicit LineBuffer(size_t capacity) : capacity_(capacity) {}
    void add(const Line &line);
    const std::deque<Line> &lines() const noexcept { return lines_; }
    uint64_t total() const noexcept { return total_; }

private:
    size_t capacity_;
    std::deque<Line> lines_;
    size_t bytes_ = 0; // text of lines_
    uint64_t total_ = 0;
};

// An output log file: PATH grows up to `limit` bytes (0: no limit), then is renamed to
// PATH.1 (PATH.1 to PATH.2 and so on, keeping `keep` old files) and started afresh.
class RotatingLog {
public:
    // Opens (appending, creating) PATH; refused with error spawn_failed.
    Outcome open(const std::string &path, uint64_t limit, uint32_t keep);
    void write_line(std::string_view text) noexcept;
    bool is_open() const noexcept { return static_cast<bool>(fd_); }

private:
    bool rotate() noexcept;
    UniqueFd fd_;
    std::string path_;
    uint64_t limit_ = 0;
    uint64_t size_ = 0;
    uint32_t keep_ = 0;
};

} // namespace lnd
