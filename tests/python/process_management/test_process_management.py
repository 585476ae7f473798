"""ln_manager -c with a real ln_daemon: dependency order of chains and diamonds (from the
recorded transitions), ready_regex gating, refused configurations, crash restarts with a
retry limit, the topic watchdog, stopping process trees, re-attaching after the manager was
SIGKILLed, the console and the `ln_manager status|start|stop` commands."""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
from pathlib import Path

from links_and_nodes.manager.processes import daemon_keys as dk
from links_and_nodes.manager.processes import daemon_launch as dl
from links_and_nodes.tools.scripting import Manager

from .conftest import LIMIT, REPO, Lab, free_daemon_port, parent, pids_with, wait_for

CHILD = Path(__file__).with_name("child.py")


def process(name: str, mode: str, *args: str, marker: str, extra: str = "") -> str:
    """A process section running child.py; `extra` adds key lines."""
    words = " ".join([sys.executable, str(CHILD), mode, *args, marker])
    return f"process {name}\ncommand: {words}\n{extra}\n\n"


def ready_at(history: list[dict[str, object]], state: str) -> float:
    return next(float(t["time"]) for t in history if t["state"] == state)  # type: ignore[arg-type]


def order(mgr: Manager, *names: str) -> list[str]:
    """Names sorted by when they became ready."""
    return sorted(names, key=lambda n: ready_at(mgr.history(n), "ready"))


def start(lab: Lab, body: str, *args: str) -> Manager:
    config = lab.write(body)
    proc = lab.manager(config, "--no-console", *args)
    lab.wait_listening(proc)
    return lab.connect()


def test_chain_and_diamond_start_in_dependency_order(lab: Lab) -> None:
    m = lab.instance
    body = "".join([
        process("a", "ready", "up", marker=m, extra="ready_regex: ^up$"),
        process("b", "ready", "up", marker=m, extra="ready_regex: up\ndepends_on: a"),
        process("c", "ready", "up", marker=m, extra="ready_regex: up\ndepends_on: a"),
        process("d", "ready", "up", marker=m, extra="ready_regex: up\ndepends_on: b, c"),
        process("e", "ready", "up", marker=m, extra="ready_regex: up\ndepends_on: d"),
    ])
    with start(lab, body) as mgr:
        mgr.start("e")
        mgr.wait_ready("all", LIMIT)
        hist = {n: mgr.history(n) for n in "abcde"}
        # every dependency was ready before its dependent was even started
        for dep, user in [("a", "b"), ("a", "c"), ("b", "d"), ("c", "d"), ("d", "e")]:
            assert ready_at(hist[dep], "ready") <= ready_at(hist[user], "started"), (dep, user)
        assert [t["state"] for t in hist["a"]] == ["starting", "started", "ready"]
        assert "matched" in str(hist["a"][-1]["reason"])
        mgr.quit()


def test_ready_regex_gates_dependents(lab: Lab) -> None:
    gate = lab.tmp / "gate"
    m = lab.instance
    body = (process("sensor", "gate", str(gate), marker=m, extra="ready_regex: ^ready")
            + process("ctrl", "ready", "up", marker=m, extra="depends_on: sensor"))
    with start(lab, body) as mgr:
        mgr.start("ctrl")
        wait_for(lambda: "waiting" in mgr.output("sensor"), "the sensor's first line")
        assert mgr.state("sensor") == "started"
        assert mgr.state("ctrl") == "starting"  # held back: no "ready" line yet
        gate.touch()
        mgr.wait_ready("all", LIMIT)
        assert ready_at(mgr.history("sensor"), "ready") <= \
            ready_at(mgr.history("ctrl"), "starting") + LIMIT
        assert mgr.history("ctrl")[-1]["state"] == "ready"
        mgr.quit()


def test_cycle_and_errors_refused_before_anything_starts(lab: Lab) -> None:
    m = lab.instance
    body = (process("a", "ready", "up", marker=m, extra="depends_on: b")
            + process("b", "ready", "up", marker=m, extra="depends_on: a\ncomand: x"))
    config = lab.write(body)
    proc = lab.manager(config, "--no-console", "--start-all")
    assert proc.wait(timeout=LIMIT) == 2
    log = lab.log()
    assert f"{config}:" in log
    assert "a -> b -> a" in log or "b -> a -> b" in log
    assert "unknown key 'comand'" in log
    assert "nothing started" in log
    assert pids_with(m) == []


def test_crash_restarts_with_backoff_then_gives_up(lab: Lab) -> None:
    body = process("crasher", "exit", "3", marker=lab.instance,
                   extra="restart: on-failure\nrestart_limit: 2\nrestart_delay: 0.05")
    with start(lab, body) as mgr:
        mgr.start("crasher")
        wait_for(lambda: any("gave up" in str(t["reason"]) for t in mgr.history("crasher")),
                 "the retry limit")
        hist = mgr.history("crasher")
        assert [t["state"] for t in hist].count("starting") == 3
        assert "exit status 3" in str(hist[-1]["reason"])
        starts = [float(t["time"]) for t in hist if t["state"] == "starting"]
        # back-off: the second wait is at least twice the configured first delay
        assert starts[2] - starts[1] >= 0.1 - 0.01
        assert mgr.state("crasher") == "failed"
        mgr.quit()


def test_watchdog_restarts_stalled_publisher(lab: Lab) -> None:
    body = process("pub", "publish", "lab.state", "40", marker=lab.instance,
                   extra="ready_regex: ^ready\nwatchdog_topic: lab.state, 50\n"
                         "restart_delay: 0.05\nrestart_limit: 1\n"
                         # it imports links_and_nodes: also without an installed copy
                         "pass_environment: PYTHONPATH")
    with start(lab, body) as mgr:
        mgr.start("pub")
        mgr.wait_ready("pub", LIMIT)
        wait_for(lambda: [t["state"] for t in mgr.history("pub")].count("starting") >= 2,
                 "the watchdog's restart")
        reasons = [str(t["reason"]) for t in mgr.history("pub")]
        assert any("watchdog: lab.state at" in r and "< 50 Hz" in r for r in reasons)
        mgr.quit()


def test_stop_kills_the_whole_tree(lab: Lab) -> None:
    body = process("tree", "tree", marker=lab.instance, extra="ready_regex: ^ready")
    with start(lab, body) as mgr:
        mgr.start("tree")
        mgr.wait_ready("tree", LIMIT)
        wait_for(lambda: len(pids_with(lab.instance)) >= 3, "child and grandchild")
        mgr.stop("tree")
        assert mgr.state("tree") == "stopped"
        wait_for(lambda: pids_with(lab.instance) == [], "no process of the tree left")
        mgr.quit()


def test_term_timeout_then_sigkill(lab: Lab) -> None:
    body = process("stubborn", "ignore-term", marker=lab.instance,
                   extra="ready_regex: ^ready\nterm_timeout: 0.3")
    with start(lab, body) as mgr:
        mgr.start("stubborn")
        mgr.wait_ready("stubborn", LIMIT)
        mgr.stop("stubborn")
        hist = mgr.history("stubborn")
        assert hist[-1]["state"] == "stopped"
        assert "SIGKILL" in str(hist[-1]["reason"])
        mgr.quit()


def test_manager_killed_processes_survive_and_new_manager_reattaches(lab: Lab) -> None:
    """The processes keep running under the daemon; the new manager re-attaches to them,
    and `c`, ready by its topic, is ready again once its publisher re-registered with the
    new manager by itself (docs/manager.md, "A manager restarted under running clients")."""
    m = lab.instance
    topic = f"pm.{m}".replace("-", "_")
    body = (process("a", "ready", "up", marker=m, extra="ready_regex: ^up$")
            + process("b", "ready", "up", marker=m, extra="depends_on: a\nready_regex: up")
            + process("c", "publish", topic, "3", marker=m,
                      # this checkout's package and ln_generate, whatever is installed
                      extra=f"ready_on_topic: {topic}\n"
                            f"environment: PYTHONPATH={REPO / 'python'}:{REPO}"))
    config = lab.write(body)
    first = lab.manager(config, "--no-console", "--start-all")
    lab.wait_listening(first)
    with lab.connect() as mgr:
        mgr.wait_ready("all", LIMIT)
        pids = {p["name"]: p["pid"] for p in mgr.status()}
    first.send_signal(signal.SIGKILL)
    first.wait()
    for pid in pids.values():
        os.kill(pid, 0)  # still running under the daemon
    second = lab.manager(config, "--no-console")
    lab.wait_listening(second)
    with lab.connect() as mgr:
        wait_for(lambda: mgr.state("c") == "ready", "c ready by its re-registered topic")
        status = {p["name"]: p for p in mgr.status()}
        assert {n: (p["state"], p["pid"]) for n, p in status.items()} == \
            {"a": ("ready", pids["a"]), "b": ("ready", pids["b"]),
             "c": ("ready", pids["c"])}
        assert f"topic {topic} has a publisher" in mgr.history("c")[-1]["reason"]
        topics = {t["name"]: t for t in mgr.topics()}
        assert topics[topic]["publishers"] == 1 and topics[topic]["published"] == 3
        assert "up" in mgr.output("a")  # recent output came back from the daemon
        mgr.quit()
    wait_for(lambda: pids_with(m) == [], "the processes stopped by quit")


def test_console_on_stdin(lab: Lab) -> None:
    body = process("a", "ready", "hello-from-a", marker=lab.instance,
                   extra="ready_regex: hello")
    config = lab.write(body)
    proc = lab.manager(config, stdin=subprocess.PIPE)
    lab.wait_listening(proc)
    assert proc.stdin is not None and proc.stdout is not None
    proc.stdin.write("start a\n")
    proc.stdin.flush()
    assert proc.stdout.readline().strip() == "starting: a"
    with lab.connect() as mgr:
        mgr.wait_ready("a", LIMIT)
    proc.stdin.write("status\noutput a -n 1\nbogus\nquit\n")
    proc.stdin.flush()
    out, _ = proc.communicate(timeout=LIMIT)
    lines = out.splitlines()
    assert lines[0].split() == ["process", "state", "pid", "node", "cpu", "%", "rss", "threads",
                                "restarts", "reason"]
    assert lines[1].split()[:2] == ["a", "ready"]
    assert "a: hello-from-a" in lines
    assert "error: unknown command 'bogus' (try help)" in lines
    assert proc.returncode == 0


def test_remote_commands_and_start_all_wait_ready(lab: Lab) -> None:
    m = lab.instance
    body = (process("a", "ready", "up", marker=m, extra="ready_regex: up")
            + process("b", "ready", "up", marker=m, extra="depends_on: a\nready_regex: up")
            + "group both\nadd members: a\nadd members: b\n")
    config = lab.write(body)
    proc = lab.manager(config, "--no-console", "--start-all", "--wait-ready")
    lab.wait_listening(proc)
    assert proc.stdout is not None
    assert proc.stdout.readline().strip() == "ln_manager: all 2 processes ready"
    addr = f"127.0.0.1:{lab.manager_port}"

    def cli(*args: str) -> subprocess.CompletedProcess[str]:
        return subprocess.run([sys.executable, "-m", "links_and_nodes.manager", *args,
                               "--manager", addr], capture_output=True, text=True,
                              env=lab.env, timeout=LIMIT)

    status = cli("status")
    assert status.returncode == 0 and "a" in status.stdout and "ready" in status.stdout
    assert cli("stop", "both").stdout.strip() == "stopped: a, b"
    assert cli("start", "b", "--wait").stdout.strip() == "ready: b"
    with lab.connect() as mgr:
        assert mgr.state("a") == "ready"  # started as b's dependency
    nope = cli("start", "nothing")
    assert nope.returncode == 1 and "no process or group named 'nothing'" in nope.stderr
    assert cli("quit").returncode == 0
    assert proc.wait(timeout=LIMIT) == 0


def test_exit_on_failure(lab: Lab) -> None:
    body = process("bad", "exit", "7", marker=lab.instance, extra="ready_regex: never")
    config = lab.write(body)
    proc = lab.manager(config, "--no-console", "--start-all", "--wait-ready",
                       "--exit-on-failure")
    lab.wait_listening(proc)
    assert proc.wait(timeout=LIMIT) == 1
    assert proc.stdout is not None
    assert "exit status 7" in proc.stdout.read()


def test_failure_that_restarts_is_not_final(lab: Lab) -> None:
    """--wait-ready --exit-on-failure waits through a failure its restart policy repairs."""
    flag = lab.tmp / "crashed"
    body = process("flaky", "crash-once", str(flag), marker=lab.instance,
                   extra="ready_regex: ^ready\nrestart: on-failure\nrestart_delay: 0.05")
    config = lab.write(body)
    proc = lab.manager(config, "--no-console", "--start-all", "--wait-ready",
                       "--exit-on-failure")
    lab.wait_listening(proc)
    assert proc.stdout is not None
    assert proc.stdout.readline().strip() == "ln_manager: all 1 processes ready"
    with lab.connect() as mgr:
        assert [t["state"] for t in mgr.history("flaky")].count("failed") == 1
        mgr.quit()
    assert proc.wait(timeout=LIMIT) == 0


def test_watchdog_restart_is_not_a_failure_for_good(lab: Lab) -> None:
    """The watchdog restarts a process even with `restart: never`: --exit-on-failure does
    not end the manager for it."""
    body = process("quiet", "ready", "up", marker=lab.instance,
                   extra="ready_regex: ^up\nwatchdog_topic: lab.nothing, 10\n"
                         "restart_delay: 0.05")
    config = lab.write(body)
    proc = lab.manager(config, "--no-console", "--start-all", "--exit-on-failure")
    lab.wait_listening(proc)
    with lab.connect() as mgr:
        wait_for(lambda: [t["state"] for t in mgr.history("quiet")].count("ready") >= 2,
                 "the watchdog's restart")
        assert proc.poll() is None
        mgr.quit()
    assert proc.wait(timeout=LIMIT) == 0


def test_daemon_killed_marks_its_processes_failed(lab: Lab) -> None:
    body = process("a", "ready", "up", marker=lab.instance, extra="ready_regex: up")
    with start(lab, body) as mgr:
        mgr.start("a")
        mgr.wait_ready("a", LIMIT)
        (daemon,) = lab.daemon_pids()
        os.kill(daemon, signal.SIGKILL)
        wait_for(lambda: mgr.state("a") == "failed", "the manager to notice")
        assert "lost the connection to the ln_daemon of node 'localhost'" in \
            mgr.history("a")[-1]["reason"]
        # a new start goes through a new daemon, which the manager starts itself
        mgr.start("a")
        mgr.wait_ready("a", LIMIT)
        assert lab.daemon_pids() not in ([], [daemon])
        mgr.quit()
    for pid in pids_with(lab.instance):  # what the killed daemon left behind
        with contextlib.suppress(ProcessLookupError):
            os.kill(pid, signal.SIGKILL)


def test_sigterm_ends_wait_ready(lab: Lab) -> None:
    body = process("never", "ready", "up", marker=lab.instance, extra="ready_regex: nope")
    config = lab.write(body)
    proc = lab.manager(config, "--no-console", "--start-all", "--wait-ready")
    lab.wait_listening(proc)
    with lab.connect() as mgr:
        wait_for(lambda: mgr.state("never") == "started", "the process to run")
    proc.send_signal(signal.SIGTERM)
    assert proc.wait(timeout=LIMIT) == 0
    wait_for(lambda: pids_with(lab.instance) == [], "the process stopped with the manager")


def test_processes_on_two_nodes_go_to_their_daemons(lab: Lab) -> None:
    """A second daemon stands in for another host: node_map + hosts route `node: arm` to
    it (its port, its address), `localhost` stays on the manager's own daemon."""
    key_file = Path(lab.env["LN_DAEMON_KEY_FILE"])
    dk.create_key_file(key_file)
    other_port = free_daemon_port()
    daemon = subprocess.run([dl.daemon_executable(), "--port", str(other_port), "--key-file",
                             str(key_file), "--log", str(lab.tmp / "other-daemon.log")],
                            capture_output=True, text=True, env=lab.env, timeout=LIMIT)
    assert daemon.returncode == 0, daemon.stderr
    m = lab.instance
    body = (f"hosts\narm-pc: lo:127.0.0.1, daemon_port:{other_port}\n\n"
            "node_map\narm: arm-pc\n\n"
            + process("remote", "ready", "up", marker=m, extra="node: arm\nready_regex: up")
            + process("local", "ready", "up", marker=m,
                      extra="depends_on: remote\nready_regex: up"))
    try:
        with start(lab, body) as mgr:
            mgr.start("local")
            mgr.wait_ready("all", LIMIT)
            nodes = {p["name"]: (p["node"], p["pid"]) for p in mgr.status()}
            assert nodes["remote"][0] == "arm" and nodes["local"][0] == "localhost"
            # each runs under its own daemon: the keeper's parent is that daemon
            other = [pid for pid in pids_with(f"--port\0{other_port}\0")
                     if parent(pid) not in pids_with(f"--port\0{other_port}\0")]
            assert parent(parent(nodes["remote"][1])) in other
            assert parent(parent(nodes["local"][1])) in lab.daemon_pids()
            mgr.quit()
    finally:
        for pid in pids_with(f"--port\0{other_port}\0"):
            with contextlib.suppress(ProcessLookupError):  # a fork that just exited
                os.kill(pid, signal.SIGKILL)
