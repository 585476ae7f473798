// One supervised process and its state machine (docs/daemon.md, "Process lifecycle"):
//   starting -> running -> stopping -> exited, or starting -> (refused, record dropped).
// Inputs are keeper reports, the keeper's exit, commands, output bytes and the clock; every
// transition is told to the Sink.  Signals and clocks go through Os, so tests can fake them.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "os.hpp"
#include "outcome.hpp"
#include "output.hpp"
#include "protocol.hpp"
#include "spec.hpp"

namespace lnd {

enum class State : uint8_t { starting = 0, running = 1, stopping = 2, exited = 3 };
const char *state_name(State s) noexcept;

class Process;

// Where a process's news goes (the server turns it into replies and events).
class Sink {
public:
    virtual ~Sink() = default;
    // The answer to SPAWN: ok, or refused with code and text.
    virtual void spawn_result(const Process &p, const Outcome &result) = 0;
    virtual void line(const Process &p, const Line &line) = 0;
    virtual void state_changed(const Process &p) = 0;
    virtual void exited(const Process &p) = 0;
};

constexpr double kKillRescanInterval = 0.1; // seconds between SIGKILL sweeps of the tree
constexpr size_t kReadChunk = 65536;        // bytes read from one output per poll round

class Process {
public:
    enum class Fd { report, out, err };

    Process(Os &os, Sink &sink, uint64_t id, uint64_t token, ProcessConfig config, LaunchSpec spec,
            Launched launched, RotatingLog log);
    Process(const Process &) = delete;
    Process &operator=(const Process &) = delete;

    // From the keeper.
    void on_report(const KeeperReport &r);
    void on_keeper_exit(int status);
    // Commands.
    Outcome stop();
    Outcome send_signal(int sig, bool group);
    // Daemon shutdown: go straight to SIGKILL.
    void kill_now();
    // Output bytes of one stream.
    void on_output(proto::Stream stream, const char *data, size_t n);
    // The real descriptors, for the poll loop (-1 when closed).
    int fd(Fd which) const noexcept;
    void on_readable(Fd which);
    // Deadlines: partial-line flushes, SIGKILL after the term timeout, SIGKILL sweeps.
    void tick();
    double next_deadline() const noexcept; // monotonic; +inf when nothing is due

    bool failed() const noexcept { return failed_; } // SPAWN refused: drop the record
    uint64_t id() const noexcept { return id_; }
    uint64_t token() const noexcept { return token_; }
    const std::string &instance() const noexcept { return config_.instance; }
    const std::string &name() const noexcept { return config_.name; }
    State state() const noexcept { return state_; }
    pid_t pid() const noexcept { return pid_; }
    pid_t keeper() const noexcept { return keeper_; }
    proto::ExitKind exit_kind() const noexcept { return exit_kind_; }
    int exit_value() const noexcept { return exit_value_; }
    double started() const noexcept { return started_; }
    double exit_time() const noexcept { return exit_time_; }
    const LineBuffer &output() const noexcept { return buffer_; }

private:
    void set_state(State s);
    void drain(Fd which);
    void read_report();
    enum class ReadResult { data, again, end };
    ReadResult read_output(Fd which);
    void close_output(Fd which);
    void emit(proto::Stream stream, std::string &&text);
    void begin_kill();

    Os &os_;
    Sink &sink_;
    uint64_t id_;
    uint64_t token_; // identifies the SPAWN request until it is answered
    ProcessConfig config_;
    LaunchSpec spec_; // kept for the wording of a setup failure
    pid_t keeper_;
    UniqueFd report_;
    UniqueFd out_;
    UniqueFd err_;
    UniqueFd slave_; // pty slave, held until the child has it
    std::string report_buf_;
    RotatingLog log_;
    LineBuffer buffer_;
    LineSplitter split_[2];   // out (or pty), err
    std::vector<Line> early_; // lines read before the start was reported
    proto::Stream out_stream_;

    State state_ = State::starting;
    bool failed_ = false;
    pid_t pid_ = 0;
    bool main_alive_ = false;
    bool stop_requested_ = false;
    bool killing_ = false;
    double deadline_ = 0; // monotonic: SIGKILL is due
    double rescan_ = 0;   // monotonic: next SIGKILL sweep
    double started_ = 0;
    double exit_time_ = 0;
    proto::ExitKind exit_kind_ = proto::ExitKind::none;
    int exit_value_ = 0;
};

} // namespace lnd
