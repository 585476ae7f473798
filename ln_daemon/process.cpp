// The state machine of one supervised process (process.hpp).  The tree of the process is
// everything below its keeper, which is a child subreaper: orphans, setsid'd or not, stay
// below it, so "the tree is empty" is exactly "the keeper has exited".
#include "process.hpp"

#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstring>
#include <sys/wait.h>
#include <unistd.h>

#include "log.hpp"

namespace lnd {

const char *state_name(State s) noexcept
{
    switch (s) {
    case State::starting:
        return "starting";
    case State::running:
        return "running";
    case State::stopping:
        return "stopping";
    case State::exited:
        return "exited";
    }
    return "?";
}

Process::Process(Os &os, Sink &sink, uint64_t id, uint64_t token, ProcessConfig config,
                 LaunchSpec spec, Launched launched, RotatingLog log)
    : os_(os), sink_(sink), id_(id), token_(token), config_(std::move(config)),
      spec_(std::move(spec)), keeper_(launched.keeper), report_(std::move(launched.report)),
      out_(std::move(launched.out)), err_(std::move(launched.err)),
      slave_(std::move(launched.slave)), log_(std::move(log)), buffer_(config_.max_output_lines),
      out_stream_(spec_.use_pty ? proto::Stream::pty : proto::Stream::out), started_(os.wall())
{}

void Process::set_state(State s)
{
    state_ = s;
    sink_.state_changed(*this);
}

void Process::on_report(const KeeperReport &r)
{
    switch (r.kind) {
    case KeeperReport::started:
        if (state_ != State::starting)
            return;
        pid_ = r.value;
        main_alive_ = true;
        slave_.reset();
        state_ = State::running;
        sink_.spawn_result(*this, outcome::ok());
        sink_.state_changed(*this);
        for (const Line &line : early_) // output that overtook the keeper's report
            sink_.line(*this, line);
        early_.clear();
        return;
    case KeeperReport::failed:
        if (state_ != State::starting)
            return;
        failed_ = true;
        slave_.reset();
        sink_.spawn_result(*this, outcome::error(proto::Err::spawn_failed,
                                                 describe_failure(spec_, r.value, r.index, r.err)));
        return;
    case KeeperReport::main_exit:
        if (!main_alive_)
            return;
        main_alive_ = false;
        if (WIFSIGNALED(r.value)) {
            exit_kind_ = proto::ExitKind::signal;
            exit_value_ = WTERMSIG(r.value);
        } else {
            exit_kind_ = proto::ExitKind::code;
            exit_value_ = WEXITSTATUS(r.value);
        }
        if (killing_)
            return;
        if (state_ == State::running) {
            // Exited by itself: whatever it left behind gets the term signal and, after the
            // term timeout, SIGKILL, as in a stop.
            os_.kill_tree(keeper_, config_.term_signal, 0);
            deadline_ = os_.monotonic() + config_.term_timeout;
            set_state(State::stopping);
        } else if (state_ == State::stopping) {
            // Its process group has had the term signal; members that left the group
            // (setsid) have not.
            os_.kill_tree(keeper_, config_.term_signal, pid_);
        }
        return;
    }
    logf("process %s/%s: unknown keeper report %d", instance().c_str(), name().c_str(), r.kind);
}

void Process::on_keeper_exit(int status)
{
    // Whatever the keeper and the tree wrote is complete now: take it in before the exit.
    drain(Fd::report);
    drain(Fd::out);
    drain(Fd::err);
    close_output(Fd::out);
    close_output(Fd::err);
    report_.reset();
    slave_.reset();
    if (state_ == State::exited || failed_)
        return;
    if (state_ == State::starting) {
        failed_ = true;
        logf("process %s/%s: keeper %d exited with status %#x before starting it",
             instance().c_str(), name().c_str(), static_cast<int>(keeper_), status);
        sink_.spawn_result(*this,
                           outcome::error(proto::Err::spawn_failed,
                                          "the process launcher died before starting the process"));
        return;
    }
    if (main_alive_) {
        // Only if someone killed the keeper: without it the tree cannot be followed any
        // more, so end what can still be reached, the process group.
        logf("process %s/%s: keeper %d died (status %#x); killing process group %d",
             instance().c_str(), name().c_str(), static_cast<int>(keeper_), status,
             static_cast<int>(pid_));
        os_.kill(-pid_, SIGKILL);
        main_alive_ = false;
        exit_kind_ = proto::ExitKind::signal;
        exit_value_ = SIGKILL;
    }
    exit_time_ = os_.wall();
    set_state(State::exited);
    sink_.exited(*this);
}

Outcome Process::stop()
{
    switch (state_) {
    case State::starting:
        return outcome::error(proto::Err::not_running, "process " + name() + " is still starting");
    case State::exited:
        return outcome::error(proto::Err::not_running, "process " + name() + " is not running");
    case State::stopping:
        stop_requested_ = true;
        return outcome::ok(); // already on its way out
    case State::running:
        break;
    }
    stop_requested_ = true;
    int rc = os_.kill(-pid_, config_.term_signal);
    if (rc != 0 && rc != -ESRCH)
        logf("process %s/%s: kill(-%d, %d): %s", instance().c_str(), name().c_str(),
             static_cast<int>(pid_), config_.term_signal, std::strerror(-rc));
    deadline_ = os_.monotonic() + config_.term_timeout;
    set_state(State::stopping);
    return outcome::ok();
}

Outcome Process::send_signal(int sig, bool group)
{
    if (!main_alive_)
        return outcome::error(proto::Err::not_running, "process " + name() + " is not running");
    if (sig < 0 || sig >= NSIG)
        return outcome::error(proto::Err::bad_request,
                              "invalid signal number " + std::to_string(sig));
    int rc = os_.kill(group ? -pid_ : pid_, sig);
    if (rc != 0)
        return outcome::error(proto::Err::os_error, "cannot send signal " + std::to_string(sig) +
                                                        " to " + name() + ": " +
                                                        std::strerror(-rc));
    return outcome::ok();
}

void Process::begin_kill()
{
    killing_ = true;
    if (main_alive_)
        os_.kill(-pid_, SIGKILL);
    os_.kill_tree(keeper_, SIGKILL, 0);
    rescan_ = os_.monotonic() + kKillRescanInterval;
}

void Process::kill_now()
{
    if (state_ == State::running || state_ == State::stopping) {
        if (state_ == State::running)
            set_state(State::stopping);
        if (!killing_)
            begin_kill();
    }
}

void Process::emit(proto::Stream stream, std::string &&text)
{
    Line line{os_.wall(), stream, std::move(text)};
    log_.write_line(line.text);
    buffer_.add(line);
    if (state_ == State::starting)
        early_.push_back(line); // events only once SPAWN is answered
    else
        sink_.line(*this, line);
}

void Process::on_output(proto::Stream stream, const char *data, size_t n)
{
    auto &split = split_[stream == proto::Stream::err ? 1 : 0];
    split.feed(data, n, os_.monotonic(),
               [&](std::string &&text) { emit(stream, std::move(text)); });
}

int Process::fd(Fd which) const noexcept
{
    switch (which) {
    case Fd::report:
        return report_.get();
    case Fd::out:
        return out_.get();
    case Fd::err:
        return err_.get();
    }
    return -1;
}

void Process::read_report()
{
    if (!report_)
        return;
    char buf[4096];
    for (;;) {
        ssize_t n = ::read(report_.get(), buf, sizeof buf);
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0) {
            if (n == 0 || errno != EAGAIN)
                report_.reset();
            break;
        }
        report_buf_.append(buf, static_cast<size_t>(n)); // a keeper writes 3 records at most
    }
    size_t done = 0;
    while (report_buf_.size() - done >= sizeof(KeeperReport) && !failed_) {
        KeeperReport r;
        std::memcpy(&r, report_buf_.data() + done, sizeof r);
        done += sizeof r;
        on_report(r);
    }
    report_buf_.erase(0, done);
}

Process::ReadResult Process::read_output(Fd which)
{
    UniqueFd &fd = which == Fd::out ? out_ : err_;
    char buf[kReadChunk];
    ssize_t n;
    do
        n = ::read(fd.get(), buf, sizeof buf);
    while (n < 0 && errno == EINTR);
    if (n > 0) {
        on_output(which == Fd::out ? out_stream_ : proto::Stream::err, buf, static_cast<size_t>(n));
        return ReadResult::data;
    }
    if (n < 0 && errno == EAGAIN)
        return ReadResult::again;
    close_output(which); // end of stream (EIO: pty slave closed)
    return ReadResult::end;
}

void Process::close_output(Fd which)
{
    UniqueFd &fd = which == Fd::out ? out_ : err_;
    auto &split = split_[which == Fd::err ? 1 : 0];
    proto::Stream stream = which == Fd::out ? out_stream_ : proto::Stream::err;
    split.flush([&](std::string &&text) { emit(stream, std::move(text)); });
    fd.reset();
}

void Process::on_readable(Fd which)
{
    if (which == Fd::report)
        read_report();
    else if (fd(which) >= 0)
        read_output(which);
}

void Process::drain(Fd which)
{
    if (which == Fd::report) {
        if (report_)
            read_report(); // reads up to the end: the keeper is gone
        return;
    }
    // Bounded: something outside the tree could still hold the writing end.
    for (int i = 0; i < 64 && fd(which) >= 0; ++i)
        if (read_output(which) != ReadResult::data)
            break;
}

void Process::tick()
{
    double now = os_.monotonic();
    for (int i = 0; i < 2; ++i) {
        if (split_[i].pending() && now >= split_[i].flush_due()) {
            proto::Stream stream = i == 1 ? proto::Stream::err : out_stream_;
            split_[i].flush([&](std::string &&text) { emit(stream, std::move(text)); });
        }
    }
    if (state_ != State::stopping)
        return;
    if (!killing_ && now >= deadline_) {
        logf("process %s/%s: still running %.3g s after the term signal; SIGKILL to its tree",
             instance().c_str(), name().c_str(), config_.term_timeout);
        begin_kill();
    } else if (killing_ && now >= rescan_) {
        os_.kill_tree(keeper_, SIGKILL, 0);
        rescan_ = now + kKillRescanInterval;
    }
}

double Process::next_deadline() const noexcept
{
    double due = HUGE_VAL;
    for (const auto &split : split_)
        if (split.pending())
            due = std::min(due, split.flush_due());
    if (state_ == State::stopping)
        due = std::min(due, killing_ ? rescan_ : deadline_);
    return due;
}

} // namespace lnd
