// waitset_tool_cpp.cpp — the C++ waitset (ln/waitset.hpp) for tests/python/waiting: each mode
// prints "ready" once attached, then what its callbacks saw, one line each; exit 0 when done.
//   data TOPIC COUNT        robot/joint_state: "sample CYCLE" per sample read in the data
//                           callback, in order; after COUNT samples "callbacks N"
//   timer PERIOD_MS CALLS   a timer from now + 5 periods: "first NS PERIOD_NS", "next_due NS"
//                           (after a spin_once(0)), then "tick COUNT NOW_NS" per callback (the
//                           third sleeps 3.5 periods); stops after CALLS callbacks
//   detach TOPIC_A TOPIC_B  "a CYCLE" / "b callback" + "b CYCLE"; stdin: "detach-b" destroys b's
//                           attachment from another thread ("detached b"), "unread-b" prints
//                           "b unread CYCLES..."; at EOF (and 3 expiries of a witness timer)
//                           "self-detaching timer fired N"
//   stop-thread             spin() ("spinning" from its first callback) until a thread, after a
//                           line on stdin, calls stop(): "stopped"
//   stop-signal             the same, ended by SIGTERM's handler calling stop()
//   allocs CALLS            a 1 ms timer writes to a pipe whose reader is attached too; after
//                           CALLS reads "allocations N ticks T reads R": N operator new calls
//                           meanwhile
//   throw                   two one-shot timers due at once, each callback throws: "caught
//                           timer a|b" per spin_once (the second one dispatches what the first
//                           left), then "then N" of one more spin_once(0)
//   serve NAME [provider]   lntest/echo NAME in group "ws", its requests through the waitset
//                           (on_requests of the group, or of the provider): "handled N" per
//                           callback; stdin's EOF ends it
// Manager from $LN_MANAGER.
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <memory>
#include <new>
#include <stdexcept>
#include <string>
#include <thread>

#include <ln/waitset.hpp>

#include "service_messages.hpp"
#include "topic_messages.hpp"

// Every operator new of the tool, counted (allocs mode).  gcc takes free() in a replaced
// operator delete for a mismatch.
#pragma GCC diagnostic ignored "-Wpragmas"
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
std::atomic<unsigned long> allocations{0};

void* operator new(std::size_t size)
{
    allocations++;
    if (void* p = std::malloc(size ? size : 1))
        return p;
    throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

namespace {

using joint_state = robot::joint_state_t;

void say(const std::string& line)
{
    std::printf("%s\n", line.c_str());
    std::fflush(stdout);
}

// Lines from stdin through the waitset: on_line(line) per line, on_eof() at its end.
template <typename L, typename E>
ln::waitset::attachment read_lines(ln::waitset& ws, L on_line, E on_eof)
{
    return ws.on_fd(0, LN_WAIT_READABLE, [on_line, on_eof, buffered = std::string()]() mutable {
        char buf[256];
        ssize_t n = read(0, buf, sizeof buf);
        if (n <= 0) {
            on_eof();
            return;
        }
        buffered.append(buf, static_cast<std::size_t>(n));
        for (std::size_t end; (end = buffered.find('\n')) != std::string::npos;) {
            std::string line = buffered.substr(0, end);
            buffered.erase(0, end + 1);
            on_line(line);
        }
    });
}

int data(const char* topic, unsigned long count)
{
    ln::client clnt("waitset_tool_cpp");
    auto port = clnt.subscribe<joint_state>(topic, 64);
    ln::waitset ws;
    unsigned long samples = 0, callbacks = 0;
    auto attached = ws.on_data(port, [&](ln::inport<joint_state>& p) {
        callbacks++;
        joint_state js;
        while (p.read(js, 0.0)) {
            say("sample " + std::to_string(js.cycle));
            if (++samples == count)
                ws.stop();
        }
    });
    say("ready");
    ws.spin();
    say("callbacks " + std::to_string(callbacks));
    return 0;
}

int timer(double period_ms, int calls)
{
    ln::waitset ws;
    const auto period_ns = static_cast<std::int64_t>(period_ms * 1e6);
    const std::int64_t first = ln::waitset::monotonic_ns() + 5 * period_ns;
    int seen = 0;
    auto ticking = ws.at(first, period_ms / 1000.0, [&](std::uint32_t n) {
        std::int64_t now = ln::waitset::monotonic_ns();
        say("tick " + std::to_string(n) + " " + std::to_string(now));
        if (++seen == 3) // fall behind: the timer must skip, not burst
            std::this_thread::sleep_for(std::chrono::nanoseconds(period_ns * 7 / 2));
        if (seen == calls)
            ws.stop();
    });
    say("first " + std::to_string(first) + " " + std::to_string(period_ns));
    ws.spin_once(0.0); // takes the attachment into account: next_due() is then the timer's
    say("next_due " + std::to_string(ws.next_due()));
    say("ready");
    ws.spin();
    return 0;
}

int detach(const char* topic_a, const char* topic_b)
{
    ln::client clnt("waitset_tool_cpp");
    auto a = clnt.subscribe<joint_state>(topic_a, 16);
    auto b = clnt.subscribe<joint_state>(topic_b, 16);
    ln::waitset ws;
    auto on_a = ws.on_data(a, [](ln::inport<joint_state>& p) {
        joint_state js;
        while (p.read(js, 0.0))
            say("a " + std::to_string(js.cycle));
    });
    auto on_b = ws.on_data(b, [](ln::inport<joint_state>& p) {
        say("b callback");
        joint_state js;
        while (p.read(js, 0.0))
            say("b " + std::to_string(js.cycle));
    });
    // A timer that ends its own attachment in its first callback must not fire again: by the
    // time a witness on the same schedule saw 3 expiries, it would have seen them too.
    const std::int64_t first = ln::waitset::monotonic_ns() + 10000000;
    int fired = 0;
    std::uint32_t witnessed = 0;
    bool eof = false;
    ln::waitset::attachment once;
    once = ws.at(first, 0.01, [&] {
        fired++;
        once = {};
    });
    auto witness = ws.at(first, 0.01, [&](std::uint32_t n) {
        witnessed += n;
        if (eof && witnessed >= 3)
            ws.stop();
    });
    std::thread detacher;
    ln::waitset::attachment commands;
    commands = read_lines(
        ws,
        [&](const std::string& line) {
            if (line == "detach-b") { // waits for this callback to return, then detaches
                detacher = std::thread([&] {
                    on_b = {};
                    say("detached b");
                });
            } else if (line == "unread-b") {
                std::string unread = "b unread";
                joint_state js;
                while (b.read(js, 0.0))
                    unread += " " + std::to_string(js.cycle);
                say(unread);
            }
        },
        [&] {
            eof = true;
            commands = {}; // stdin stays readable at its end
            if (witnessed >= 3)
                ws.stop();
        });
    say("ready");
    ws.spin();
    if (detacher.joinable())
        detacher.join();
    say("self-detaching timer fired " + std::to_string(fired));
    return 0;
}

std::atomic<ln::waitset*> signalled{nullptr};

extern "C" void on_signal(int)
{
    if (ln::waitset* ws = signalled.load())
        ws->stop();
}

int stop_from(bool signal)
{
    ln::waitset ws;
    auto spinning = ws.at(ln::waitset::monotonic_ns(), 0.0, [] { say("spinning"); }); // once
    std::thread stopper;
    if (signal) {
        signalled = &ws;
        struct sigaction sa;
        std::memset(&sa, 0, sizeof sa);
        sa.sa_handler = on_signal;
        sigemptyset(&sa.sa_mask);
        sigaction(SIGTERM, &sa, nullptr);
    } else {
        stopper = std::thread([&] {
            char buf[64];
            if (read(0, buf, sizeof buf) >= 0)
                ws.stop();
        });
    }
    say("ready");
    ws.spin();
    signalled = nullptr;
    if (stopper.joinable())
        stopper.join();
    say("stopped");
    return 0;
}

// Timer and descriptor callbacks that allocate nothing themselves: what spin() allocates.
int allocs(int calls)
{
    int pipe_fds[2];
    if (pipe(pipe_fds) != 0)
        return std::perror("pipe"), 1;
    ln::waitset ws;
    int ticks = 0, reads = 0;
    // std::functions of lambdas too big for their inline buffer: a copy per event allocates.
    std::function<void()> on_pipe = [&ws, &reads, &calls, &pipe_fds] {
        char c;
        if (read(pipe_fds[0], &c, 1) == 1 && ++reads == calls)
            ws.stop();
    };
    std::function<void(std::uint32_t)> on_tick = [&ws, &ticks, &calls, &pipe_fds](std::uint32_t) {
        if (++ticks > 2 * calls || write(pipe_fds[1], "x", 1) != 1) // (a bound against hangs)
            ws.stop();
    };
    auto reader = ws.on_fd(pipe_fds[0], LN_WAIT_READABLE, on_pipe);
    auto timer = ws.every(0.001, on_tick);
    say("ready");
    unsigned long before = allocations.load();
    ws.spin();
    unsigned long during = allocations.load() - before;
    say("allocations " + std::to_string(during) + " ticks " + std::to_string(ticks) + " reads " +
        std::to_string(reads));
    close(pipe_fds[0]);
    close(pipe_fds[1]);
    return 0;
}

// An exception leaves spin_once; the event after it in the batch is not lost.
int throwing()
{
    ln::waitset ws;
    const std::int64_t first = ln::waitset::monotonic_ns() + 1000000;
    auto a = ws.at(first, 0.0, [] { throw std::runtime_error("timer a"); });
    auto b = ws.at(first, 0.0, [] { throw std::runtime_error("timer b"); });
    say("ready");
    for (double timeout : {-1.0, 0.0}) {
        try {
            say("no exception, " + std::to_string(ws.spin_once(timeout)) + " events");
        } catch (const std::runtime_error& e) {
            say(std::string("caught ") + e.what());
        }
    }
    say("then " + std::to_string(ws.spin_once(0.0)));
    return 0;
}

int serve(const char* name, bool by_provider)
{
    using echo = lntest::echo_t;
    ln::client clnt("waitset_tool_cpp");
    auto provider = clnt.provide_service<echo>(
        name,
        [](ln::service_provider<echo>::call& c) {
            c.resp.caller = c.req.caller;
            c.resp.seq = c.req.seq;
            c.resp.text_len = c.req.text_len; // the request's text lives until we return
            c.resp.text = c.req.text;
        },
        "ws");
    ln::waitset ws;
    auto handled = [](int n) { say("handled " + std::to_string(n)); };
    ln::waitset::attachment requests;
    if (by_provider)
        requests = ws.on_requests(
            *provider, [&] { handled(clnt.wait_and_handle_service_group_requests("ws", 0.0)); });
    else
        requests = ws.on_requests(clnt, "ws", handled);
    auto commands = read_lines(
        ws, [](const std::string&) {}, [&] { ws.stop(); });
    say("ready");
    ws.spin();
    return 0;
}

int usage()
{
    std::fprintf(stderr, "usage: see the top of waitset_tool_cpp.cpp\n");
    return 2;
}

int run(int argc, char** argv)
{
    std::string mode = argc > 1 ? argv[1] : "";
    if (mode == "data" && argc == 4)
        return data(argv[2], std::strtoul(argv[3], nullptr, 10));
    if (mode == "timer" && argc == 4)
        return timer(std::atof(argv[2]), std::atoi(argv[3]));
    if (mode == "detach" && argc == 4)
        return detach(argv[2], argv[3]);
    if ((mode == "stop-thread" || mode == "stop-signal") && argc == 2)
        return stop_from(mode == "stop-signal");
    if (mode == "throw" && argc == 2)
        return throwing();
    if (mode == "allocs" && argc == 3)
        return allocs(std::atoi(argv[2]));
    if (mode == "serve" && (argc == 3 || (argc == 4 && std::strcmp(argv[3], "provider") == 0)))
        return serve(argv[2], argc == 4);
    return usage();
}

} // namespace

int main(int argc, char** argv)
{
    try {
        return run(argc, argv);
    } catch (const ln::error& e) {
        std::fprintf(stderr, "waitset_tool_cpp: %s (%d)\n", e.what(), e.code());
        return 1;
    }
}
