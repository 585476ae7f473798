// Unit tests of the process state machine and the supervisor with a fake OS layer: the
// clock is set by hand, kill/kill_tree are recorded, keeper reports and reaping are fed in,
// so every transition and every signal the daemon sends can be checked exactly.
#include <cerrno>
#include <cstdio>
#include <cmath>
#include <csignal>
#include <deque>
#include <string>
#include <sys/resource.h>
#include <sys/wait.h>
#include <vector>

#include "daemon_test.hpp"
#include "process.hpp"
#include "spec.hpp"
#include "supervisor.hpp"

using namespace lnd;

namespace {

class FakeOs final : public Os {
public:
    double now = 100.0;
    pid_t next_keeper = 1000;
    bool fail_launch = false;
    std::vector<std::string> calls; // "kill -42 15", "tree 1000 9 skip 0"
    std::deque<std::pair<pid_t, int>> exits;

    double monotonic() noexcept override { return now; }
    double wall() noexcept override { return 1e9 + now; }
    Outcome launch(const LaunchSpec &spec, Launched &out) override
    {
        if (fail_launch)
            return outcome::error(proto::Err::spawn_failed, "cannot fork: fake");
        out.keeper = next_keeper++;
        calls.push_back("launch " + spec.argv[0]);
        return outcome::ok();
    }
    int kill(pid_t pid, int sig) noexcept override
    {
        calls.push_back("kill " + std::to_string(pid) + " " + std::to_string(sig));
        return 0;
    }
    int kill_tree(pid_t keeper, int sig, pid_t skip) noexcept override
    {
        calls.push_back("tree " + std::to_string(keeper) + " " + std::to_string(sig) + " skip " +
                        std::to_string(skip));
        return 0;
    }
    bool reap(pid_t &pid, int &status) noexcept override
    {
        if (exits.empty())
            return false;
        pid = exits.front().first;
        status = exits.front().second;
        exits.pop_front();
        return true;
    }
    std::string take_calls()
    {
        std::string all;
        for (const auto &c : calls)
            all += (all.empty() ? "" : "; ") + c;
        calls.clear();
        return all;
    }
};

class RecordingSink final : public Sink {
public:
    std::vector<std::string> events;
    void spawn_result(const Process &p, const Outcome &result) override
    {
        events.push_back(!result.failed()
                             ? "spawned " + p.name() + " pid " + std::to_string(p.pid())
                             : "refused " + p.name() + " " +
                                   std::to_string(static_cast<int>(result.code)) + ": " +
                                   result.text);
    }
    void line(const Process &p, const Line &line) override
    {
        events.push_back("line " + p.name() + " " + std::to_string(static_cast<int>(line.stream)) +
                         " " + line.text);
    }
    void state_changed(const Process &p) override
    {
        events.push_back(std::string("state ") + p.name() + " " + state_name(p.state()));
    }
    void exited(const Process &p) override
    {
        events.push_back("exited " + p.name() + " kind " +
                         std::to_string(static_cast<int>(p.exit_kind())) + " value " +
                         std::to_string(p.exit_value()));
    }
    std::string take()
    {
        std::string all;
        for (const auto &e : events)
            all += (all.empty() ? "" : "; ") + e;
        events.clear();
        return all;
    }
};

SpawnRequest request(const std::string &name, const std::string &cmd = "sleep")
{
    SpawnRequest r;
    r.name = name;
    r.argv = {cmd, "1000"};
    r.env = {"PATH=/usr/bin:/bin"};
    r.term_timeout = 5.0;
    return r;
}

struct Fixture {
    FakeOs os;
    RecordingSink sink;
    Supervisor sup{os, sink};
};

// Spawns and feeds the keeper's "started" report.
Process *start(Fixture &f, const std::string &instance, const SpawnRequest &req, pid_t pid)
{
    proto::Err code;
    std::string error;
    pid_t keeper = f.os.next_keeper;
    if (!passed(f.sup.spawn(instance, req, 7), code, error)) {
        std::fprintf(stderr, "    spawn refused: %s\n", error.c_str());
        return nullptr;
    }
    Process *p = f.sup.find_keeper(keeper);
    if (!p)
        return nullptr;
    p->on_report({KeeperReport::started, pid, 0, 0});
    return p;
}

int exit_status(int code) { return code << 8; }
int signal_status(int sig) { return sig; }

void test_start_and_natural_exit()
{
    Fixture f;
    Process *p = start(f, "inst", request("a"), 42);
    LN_CHECK(p != nullptr);
    if (!p)
        return;
    CHECK_STR(f.sink.take(), "spawned a pid 42; state a running");
    CHECK_STR(f.os.take_calls(), "launch sleep");
    LN_CHECK(p->state() == State::running);

    // The main process exits by itself: what it left behind gets the term signal.
    p->on_report({KeeperReport::main_exit, exit_status(3), 0, 0});
    LN_CHECK(p->state() == State::stopping);
    CHECK_STR(f.os.take_calls(), "tree 1000 15 skip 0");
    CHECK_STR(f.sink.take(), "state a stopping");

    // The keeper exits: the tree is empty, the exit is reported with the main's status.
    f.os.exits.push_back({1000, 0});
    f.sup.reap();
    LN_CHECK(p->state() == State::exited);
    LN_CHECK_EQ(p->exit_kind(), proto::ExitKind::code);
    LN_CHECK_EQ(p->exit_value(), 3);
    CHECK_STR(f.sink.take(), "state a exited; exited a kind 1 value 3");
    CHECK_STR(f.os.take_calls(), "");
}

void test_stop_then_sigkill_after_timeout()
{
    Fixture f;
    SpawnRequest req = request("b");
    req.term_signal = SIGINT;
    req.term_timeout = 5.0;
    Process *p = start(f, "inst", req, 50);
    LN_CHECK(p != nullptr);
    if (!p)
        return;
    f.sink.take();
    f.os.take_calls();
    proto::Err code;
    std::string error;
    LN_CHECK(passed(p->stop(), code, error));
    CHECK_STR(f.os.take_calls(), "kill -50 2");
    CHECK_STR(f.sink.take(), "state b stopping");
    LN_CHECK(passed(p->stop(), code, error)); // a second STOP is harmless
    CHECK_STR(f.os.take_calls(), "");

    f.os.now += 4.9;
    LN_CHECK(p->next_deadline() > f.os.now);
    f.sup.tick();
    CHECK_STR(f.os.take_calls(), "");
    f.os.now += 0.1;
    f.sup.tick();
    CHECK_STR(f.os.take_calls(), "kill -50 9; tree 1000 9 skip 0");
    // The tree is swept again until the keeper is gone.
    f.os.now += kKillRescanInterval;
    f.sup.tick();
    CHECK_STR(f.os.take_calls(), "tree 1000 9 skip 0");

    p->on_report({KeeperReport::main_exit, signal_status(SIGKILL), 0, 0});
    CHECK_STR(f.os.take_calls(), ""); // already killing: no term signal
    f.os.exits.push_back({1000, 0});
    f.sup.reap();
    LN_CHECK(p->state() == State::exited);
    CHECK_STR(f.sink.take(), "state b exited; exited b kind 2 value 9");
    LN_CHECK(std::isinf(p->next_deadline()));
}

void test_stop_main_exits_leftovers_get_term()
{
    Fixture f;
    Process *p = start(f, "inst", request("c"), 60);
    LN_CHECK(p != nullptr);
    if (!p)
        return;
    f.sink.take();
    f.os.take_calls();
    proto::Err code;
    std::string error;
    passed(p->stop(), code, error);
    CHECK_STR(f.os.take_calls(), "kill -60 15");
    // The group obeyed; members that left the group (setsid) get the term signal now.
    p->on_report({KeeperReport::main_exit, signal_status(SIGTERM), 0, 0});
    CHECK_STR(f.os.take_calls(), "tree 1000 15 skip 60");
    LN_CHECK(p->state() == State::stopping);
    // One of them ignores it: SIGKILL once the term timeout is over, not to the dead group.
    f.os.now += 5.0;
    f.sup.tick();
    CHECK_STR(f.os.take_calls(), "tree 1000 9 skip 0");
    f.os.exits.push_back({1000, 0});
    f.sup.reap();
    CHECK_STR(f.sink.take(), "state c stopping; state c exited; exited c kind 2 value 15");
}

void test_exec_failure_is_a_spawn_error()
{
    Fixture f;
    proto::Err code;
    std::string error;
    pid_t keeper = f.os.next_keeper;
    LN_CHECK(passed(f.sup.spawn("inst", request("d", "no-such-cmd"), 7), code, error));
    Process *p = f.sup.find_keeper(keeper);
    LN_CHECK(p != nullptr);
    if (!p)
        return;
    LN_CHECK(f.sup.list("inst").empty()); // not listed before SPAWN is answered
    KeeperReport failed{KeeperReport::failed, static_cast<int32_t>(Stage::exec), 0, ENOENT};
    p->on_report(failed);
    CHECK_STR(f.sink.take(), "refused d 9: command not found: no-such-cmd");
    LN_CHECK(p->failed());
    // The supervisor drops the record after the report was read; the keeper is still to
    // be reaped, and a shutting-down daemon waits for it.
    f.sup.on_fd({p->id(), Process::Fd::report});
    LN_CHECK_EQ(f.sup.size(), 0);
    LN_CHECK_EQ(f.sup.stray_keepers(), 1);
    f.os.exits.push_back({keeper, exit_status(0)});
    f.sup.reap();
    LN_CHECK_EQ(f.sup.stray_keepers(), 0);
    LN_CHECK(f.sup.list("inst").empty());
    // The name is free again.
    LN_CHECK(start(f, "inst", request("d"), 70) != nullptr);
}

void test_keeper_dies_before_start()
{
    Fixture f;
    proto::Err code;
    std::string error;
    pid_t keeper = f.os.next_keeper;
    LN_CHECK(passed(f.sup.spawn("inst", request("e"), 7), code, error));
    f.os.exits.push_back({keeper, signal_status(SIGKILL)});
    f.sup.reap();
    std::string events = f.sink.take();
    LN_CHECK(events.find("refused e 9: the process launcher died") == 0);
    LN_CHECK_EQ(f.sup.size(), 0);
}

void test_names_and_forget()
{
    Fixture f;
    Process *p = start(f, "inst", request("f"), 80);
    LN_CHECK(p != nullptr);
    if (!p)
        return;
    proto::Err code;
    std::string error;
    LN_CHECK(!passed(f.sup.spawn("inst", request("f"), 8), code, error));
    LN_CHECK_EQ(code, proto::Err::already_running);
    CHECK_STR(error, "process f is already running (pid 80)");
    LN_CHECK(!passed(f.sup.forget("inst", "f"), code, error));
    LN_CHECK_EQ(code, proto::Err::still_running);
    LN_CHECK(!passed(f.sup.forget("inst", "nope"), code, error));
    LN_CHECK_EQ(code, proto::Err::unknown_process);

    p->on_report({KeeperReport::main_exit, exit_status(0), 0, 0});
    f.os.exits.push_back({1000, 0});
    f.sup.reap();
    LN_CHECK(p->state() == State::exited);
    LN_CHECK(!passed(p->stop(), code, error));
    LN_CHECK_EQ(code, proto::Err::not_running);
    LN_CHECK(!passed(p->send_signal(SIGUSR1, false), code, error));
    LN_CHECK_EQ(code, proto::Err::not_running);
    // Spawning the name again replaces the exited record.
    Process *again = start(f, "inst", request("f"), 81);
    LN_CHECK(again != nullptr && again->pid() == 81);
    LN_CHECK_EQ(f.sup.list("inst").size(), 1);
    // Forget of an exited record.
    Process *g = start(f, "inst", request("g"), 82);
    LN_CHECK(g != nullptr);
    if (!g)
        return;
    g->on_report({KeeperReport::main_exit, exit_status(1), 0, 0});
    f.os.exits.push_back({1002, 0});
    f.sup.reap();
    LN_CHECK(passed(f.sup.forget("inst", "g"), code, error));
    LN_CHECK_EQ(f.sup.list("inst").size(), 1);
}

void test_instances_are_separate()
{
    Fixture f;
    LN_CHECK(start(f, "one", request("p"), 90) != nullptr);
    LN_CHECK(start(f, "two", request("p"), 91) != nullptr); // same name, other instance
    LN_CHECK(start(f, "two", request("q"), 92) != nullptr);
    LN_CHECK_EQ(f.sup.list("one").size(), 1);
    LN_CHECK_EQ(f.sup.list("two").size(), 2);
    LN_CHECK_EQ(f.sup.list("three").size(), 0);
    Process *p = nullptr;
    Outcome o = f.sup.find("one", "q", p);
    LN_CHECK(o.failed() && p == nullptr);
    LN_CHECK_EQ(o.code, proto::Err::unknown_process);
    LN_CHECK(!f.sup.find("one", "p", p).failed());
    LN_CHECK(p != nullptr && p->pid() == 90);
}

void test_signals()
{
    Fixture f;
    Process *p = start(f, "inst", request("s"), 100);
    LN_CHECK(p != nullptr);
    if (!p)
        return;
    f.os.take_calls();
    proto::Err code;
    std::string error;
    LN_CHECK(passed(p->send_signal(SIGUSR1, false), code, error));
    LN_CHECK(passed(p->send_signal(SIGUSR2, true), code, error));
    CHECK_STR(f.os.take_calls(), "kill 100 10; kill -100 12");
    LN_CHECK(!passed(p->send_signal(NSIG, false), code, error));
    LN_CHECK_EQ(code, proto::Err::bad_request);
}

void test_output_lines()
{
    Fixture f;
    SpawnRequest req = request("o");
    req.max_output_lines = 3;
    req.use_pty = false;
    Process *p = start(f, "inst", req, 110);
    LN_CHECK(p != nullptr);
    if (!p)
        return;
    f.sink.take();
    const char chunk[] = "one\ntwo\r\nthr";
    p->on_output(proto::Stream::out, chunk, sizeof chunk - 1);
    CHECK_STR(f.sink.take(), "line o 1 one; line o 1 two");
    // The partial line waits for its end, at most kPartialFlushDelay.
    LN_CHECK(p->next_deadline() <= f.os.now + kPartialFlushDelay);
    f.os.now += kPartialFlushDelay / 2;
    f.sup.tick();
    CHECK_STR(f.sink.take(), "");
    p->on_output(proto::Stream::out, "ee", 2);
    f.os.now += kPartialFlushDelay / 2;
    f.sup.tick();
    CHECK_STR(f.sink.take(), "line o 1 three");
    p->on_output(proto::Stream::err, "oops\n", 5);
    p->on_output(proto::Stream::out, "five\n", 5);
    CHECK_STR(f.sink.take(), "line o 2 oops; line o 1 five");
    // Bounded: the last three of five lines are kept.
    const auto &lines = p->output().lines();
    LN_CHECK_EQ(lines.size(), 3);
    LN_CHECK_EQ(p->output().total(), 5);
    CHECK_STR(lines.front().text, "three");
    CHECK_STR(lines.back().text, "five");
    // A line longer than kMaxLineBytes comes in pieces.
    std::string longline(kMaxLineBytes + 10, 'x');
    longline += '\n';
    p->on_output(proto::Stream::out, longline.data(), longline.size());
    LN_CHECK_EQ(p->output().total(), 7);
    LN_CHECK_EQ(p->output().lines().back().text.size(), 10);
}

void test_output_before_start_waits_for_the_reply()
{
    Fixture f;
    proto::Err code;
    std::string error;
    pid_t keeper = f.os.next_keeper;
    LN_CHECK(passed(f.sup.spawn("inst", request("early"), 7), code, error));
    Process *p = f.sup.find_keeper(keeper);
    LN_CHECK(p != nullptr);
    if (!p)
        return;
    p->on_output(proto::Stream::pty, "hello\n", 6);
    CHECK_STR(f.sink.take(), "");
    p->on_report({KeeperReport::started, 120, 0, 0});
    CHECK_STR(f.sink.take(), "spawned early pid 120; state early running; line early 0 hello");
}

void test_shutdown_kills()
{
    Fixture f;
    Process *p = start(f, "inst", request("k"), 130);
    LN_CHECK(p != nullptr);
    if (!p)
        return;
    f.os.take_calls();
    f.sup.stop_all();
    CHECK_STR(f.os.take_calls(), "kill -130 15");
    LN_CHECK_EQ(f.sup.alive(), 1);
    f.sup.kill_all();
    CHECK_STR(f.os.take_calls(), "kill -130 9; tree 1000 9 skip 0");
    p->on_report({KeeperReport::main_exit, signal_status(SIGKILL), 0, 0});
    f.os.exits.push_back({1000, 0});
    f.sup.reap();
    LN_CHECK_EQ(f.sup.alive(), 0);
}

void test_second_shutdown_signal_kills_a_process_still_starting()
{
    // The second SIGTERM means SIGKILL now, also for a process whose start is only reported
    // after it: it must not get the term signal and a term timeout instead.
    Fixture f;
    proto::Err code;
    std::string error;
    pid_t keeper = f.os.next_keeper;
    SpawnRequest req = request("late");
    req.term_timeout = 1e6;
    LN_CHECK(passed(f.sup.spawn("inst", req, 7), code, error));
    Process *p = f.sup.find_keeper(keeper);
    LN_CHECK(p != nullptr);
    if (!p)
        return;
    f.sup.stop_all();
    f.sup.kill_all();
    f.os.take_calls();
    p->on_report({KeeperReport::started, 140, 0, 0});
    f.sup.tick();
    CHECK_STR(f.os.take_calls(), "kill -140 9; tree 1000 9 skip 0");
    LN_CHECK(p->state() == State::stopping);
}

void test_launch_failure()
{
    Fixture f;
    f.os.fail_launch = true;
    proto::Err code;
    std::string error;
    LN_CHECK(!passed(f.sup.spawn("inst", request("l"), 7), code, error));
    LN_CHECK_EQ(code, proto::Err::spawn_failed);
    CHECK_STR(error, "cannot fork: fake");
    LN_CHECK_EQ(f.sup.size(), 0);
}

std::string check(SpawnRequest req)
{
    LaunchSpec launch;
    ProcessConfig config;
    Outcome o = check_spawn(req, launch, config);
    return o.failed() ? o.text : "ok";
}

void test_spawn_checks()
{
    CHECK_STR(check(request("x")), "ok");
    SpawnRequest r = request("x");
    r.policy = "SCHED_FIFO";
    r.priority = 0;
    CHECK_STR(check(r), "priority 0 is out of range for SCHED_FIFO (1..99)");
    r.priority = 50;
    CHECK_STR(check(r), "ok");
    r.policy = "rr";
    CHECK_STR(check(r), "ok");
    r.policy = "SCHED_DEADLINE";
    LN_CHECK(check(r).find("unknown scheduling policy 'SCHED_DEADLINE'") == 0);
    r = request("x");
    r.priority = -21;
    CHECK_STR(check(r), "nice value -21 is out of range for SCHED_OTHER (-20..19)");
    r = request("x");
    r.rlimits = {{"nofile", 100, 50}};
    CHECK_STR(check(r), "resource limit nofile: soft limit 100 is above the hard limit 50");
    r.rlimits = {{"RLIMIT_NOFILE", 50, -1}, {"core", -1, -1}};
    CHECK_STR(check(r), "ok");
    r.rlimits = {{"bogus", 1, 1}};
    LN_CHECK(check(r).find("unknown resource limit 'bogus'") == 0);
    r = request("x");
    r.cwd = "relative/dir";
    CHECK_STR(check(r), "working directory 'relative/dir' is not an absolute path");
    r = request("x");
    r.env = {"NOEQUALS"};
    LN_CHECK(check(r).find("invalid environment entry 'NOEQUALS'") == 0);
    r = request("x");
    r.shell = true;
    CHECK_STR(check(r), "a shell command is one string, got 2");
    r = request("x");
    r.argv.clear();
    CHECK_STR(check(r), "empty command");
    r = request("bad\nname");
    LN_CHECK(check(r).find("invalid process name") == 0);
    r = request("x");
    r.term_signal = 0;
    CHECK_STR(check(r), "invalid term signal 0");
    r = request("x");
    r.affinity = {5000};
    LN_CHECK(check(r).find("CPU 5000 in the affinity list is out of range") == 0);
}

void test_failure_texts()
{
    LaunchSpec s;
    s.argv = {"prog"};
    s.cwd = "/nowhere";
    s.rlimits = {{RLIMIT_NOFILE, "nofile", 10, 20}};
    s.policy = SCHED_FIFO;
    s.priority = 80;
    s.affinity = {1, 3};
    auto text = [&](Stage stage, int err) {
        return describe_failure(s, static_cast<int32_t>(stage), 0, err);
    };
    CHECK_STR(text(Stage::exec, ENOENT), "command not found: prog");
    CHECK_STR(text(Stage::chdir, ENOENT),
              "cannot change directory to '/nowhere': No such file or directory");
    CHECK_STR(text(Stage::rlimit, EPERM),
              "cannot set resource limit nofile (soft 10, hard 20): Operation not permitted");
    LN_CHECK(text(Stage::scheduler, EPERM)
                 .find("cannot set scheduling policy SCHED_FIFO with priority 80: Operation not "
                       "permitted (needs root") == 0);
    CHECK_STR(text(Stage::affinity, EINVAL), "cannot set CPU affinity to [1,3]: Invalid argument");
    s.argv = {"/opt/prog"};
    CHECK_STR(text(Stage::exec, EACCES), "cannot execute '/opt/prog': Permission denied");
}

} // namespace

int main()
{
    LN_TEST_RUN(test_start_and_natural_exit);
    LN_TEST_RUN(test_stop_then_sigkill_after_timeout);
    LN_TEST_RUN(test_stop_main_exits_leftovers_get_term);
    LN_TEST_RUN(test_exec_failure_is_a_spawn_error);
    LN_TEST_RUN(test_keeper_dies_before_start);
    LN_TEST_RUN(test_names_and_forget);
    LN_TEST_RUN(test_instances_are_separate);
    LN_TEST_RUN(test_signals);
    LN_TEST_RUN(test_output_lines);
    LN_TEST_RUN(test_output_before_start_waits_for_the_reply);
    LN_TEST_RUN(test_shutdown_kills);
    LN_TEST_RUN(test_second_shutdown_signal_kills_a_process_still_starting);
    LN_TEST_RUN(test_launch_failure);
    LN_TEST_RUN(test_spawn_checks);
    LN_TEST_RUN(test_failure_texts);
    LN_TEST_EXIT();
}
