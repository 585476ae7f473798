// The daemon's log: one line per event, "TIME ln_daemon[PID]: text", written with one
// write(2) so lines never interleave.  Goes to stderr until log_open() names a file.
#pragma once

#include <string>

namespace lnd {

struct Outcome; // outcome.hpp, which uses logf()

// Opens (appending, creating 0640) the log file; refused with error os_error.  Called again
// on SIGHUP to follow a rotated file.
Outcome log_open(const std::string &path);
// Sends the log to /dev/null (a detached daemon without --log).
void log_discard() noexcept;
void logf(const char *fmt, ...) noexcept __attribute__((format(printf, 1, 2)));

} // namespace lnd
