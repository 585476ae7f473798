"""examples/robot/robot.lnc: its model as the reader loads it, and the whole system run end to
end by `ln_manager -c robot.lnc --start-all --wait-ready --exit-on-failure --no-console` with a
private instance, manager port, ln_daemon (port and key file) and runtime directory.  Through
the scripting API: every process ready, started in dependency order (from the recorded
transitions), the supervisor reporting the tracking error and the refused gains; after `quit`
no process of the demo and no shared-memory segment of the instance is left.  The daemon the
manager started is ended at the end, whatever happened."""

from __future__ import annotations

import os
import re
import shlex
import signal
import subprocess
import sys
import time
import uuid
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest
from polling import free_daemon_port, free_port, wait_for

from links_and_nodes.manager.config import load, model
from links_and_nodes.manager.frontends.launch import segments
from links_and_nodes.tools.scripting import Manager, connect

REPO = Path(__file__).resolve().parents[3]
CONFIG = REPO / "examples" / "robot" / "robot.lnc"
DAEMON = REPO / "build" / "release" / "ln_daemon" / "ln_daemon"
LIMIT = 60.0  # upper bound for anything to happen, never a measurement
TRACKING = re.compile(r"^t=\d+ s tracking error rms +[\d.]+ mrad, max +[\d.]+ mrad "
                      r"\(joint \d\), \d+ cycles, gains '(\w+)'")


# ---- the model ----------------------------------------------------------------------------
def test_model() -> None:
    config = load(CONFIG, env={"LN_DEMO_PORT": "23456"})
    assert config.instance.name == "robot_demo"
    assert config.instance.manager == ":23456"
    assert list(config.processes) == ["arm/sensor", "arm/controller", "supervisor"]
    sensor, controller, supervisor = config.processes.values()

    assert sensor.ready_on_topic == "arm.state" and sensor.depends_on == []
    assert controller.ready_on_service == "arm.set_gains"
    assert controller.depends_on == ["arm/sensor"]
    assert controller.restart == model.Restart.ON_FAILURE
    assert supervisor.depends_on == ["arm/controller"]
    assert supervisor.ready_regex is not None
    assert re.search(supervisor.ready_regex, "arm.set_gains 'soft': accepted")
    assert not re.search(supervisor.ready_regex, "arm.set_gains 'unsafe': refused (...)")
    assert "PYTHONPATH" in supervisor.pass_environment
    assert all(p.term_timeout <= 5 for p in config.processes.values())
    assert config.groups["arm"].members == ["arm/sensor", "arm/controller"]

    build = REPO / "build" / "release" / "examples" / "robot"
    assert shlex.split(sensor.command) == [str(build / "arm_sensor"), "--rate", "1000"]
    assert shlex.split(controller.command) == [str(build / "arm_controller")]
    argv = shlex.split(supervisor.command)
    assert argv[0] == sys.executable  # the interpreter running the manager
    assert argv[1] == str(CONFIG.parent / "supervisor.py") and Path(argv[1]).is_file()


def test_model_defaults_and_overrides() -> None:
    env = {k: v for k, v in os.environ.items() if k not in ("LN_DEMO_PORT", "LN_PYTHON")}
    assert load(CONFIG, env=env).instance.manager == ":54414"
    config = load(CONFIG, env={**env, "LN_PYTHON": "/opt/py/bin/python3"},
                  defines={"variant": "debug", "rate": "500"})
    assert config.processes["supervisor"].command.startswith("/opt/py/bin/python3 ")
    assert shlex.split(config.processes["arm/sensor"].command) == [
        str(REPO / "build" / "debug" / "examples" / "robot" / "arm_sensor"), "--rate", "500"]


# ---- end to end ---------------------------------------------------------------------------


def live(pid: int) -> bool:
    """Whether pid is a process that has not exited (a zombie has)."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return False
    return stat.rsplit(")", 1)[1].split()[0] != "Z"


def pids_with_environment(entry: str) -> list[int]:
    """Live processes of ours whose environment holds `entry` ("NAME=VALUE")."""
    found = []
    needle = entry.encode() + b"\0"
    for name in os.listdir("/proc"):
        if not name.isdigit() or int(name) == os.getpid():
            continue
        try:
            environ = Path(f"/proc/{name}/environ").read_bytes()
        except OSError:
            continue
        if (environ.startswith(needle) or b"\0" + needle in environ) and live(int(name)):
            found.append(int(name))
    return found


@dataclass
class Demo:
    """One run of robot.lnc and everything private to it."""

    tmp: Path
    instance: str
    manager_port: int
    daemon_port: int
    env: dict[str, str]
    config: Path = CONFIG
    proc: subprocess.Popen[str] | None = None

    @property
    def runtime(self) -> Path:
        return Path(self.env["LN_RUNTIME_DIR"])

    def log(self) -> str:
        path = self.tmp / "manager.log"
        return path.read_text(errors="replace") if path.exists() else ""

    def start(self) -> None:
        with open(self.tmp / "manager.log", "w") as log:
            self.proc = subprocess.Popen(
                [sys.executable, "-m", "links_and_nodes.manager", "-c", str(self.config),
                 "--instance", self.instance, "--start-all", "--wait-ready",
                 "--ready-timeout", str(LIMIT), "--exit-on-failure", "--no-console"],
                stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=log, text=True,
                env=self.env)

    def stdout_line(self) -> str:
        assert self.proc is not None and self.proc.stdout is not None
        return self.proc.stdout.readline()

    def daemon_pids(self) -> list[int]:
        """The ln_daemon the manager started: the pid its log names, and (should the log be
        missing) any live daemon whose command line has this test's port and key file."""
        pids = set()
        log = self.runtime / f"ln_daemon-{self.daemon_port}.log"
        if log.exists():
            pids |= {int(m) for m in re.findall(r"ln_daemon\[(\d+)\]: listening on",
                                                  log.read_text(errors="replace"))}
        key = self.env["LN_DAEMON_KEY_FILE"].encode()
        for name in os.listdir("/proc"):
            if not name.isdigit():
                continue
            try:
                cmdline = Path(f"/proc/{name}/cmdline").read_bytes().split(b"\0")
            except OSError:
                continue
            if (cmdline[0].endswith(b"ln_daemon") and key in cmdline
                    and str(self.daemon_port).encode() in cmdline):
                pids.add(int(name))
        return sorted(pid for pid in pids if live(pid))

    def demo_processes(self) -> list[int]:
        """Processes the daemon started for this run: the scheduler gives each this run's
        manager address (the manager and the daemon have their own environment)."""
        return pids_with_environment(f"LN_MANAGER=127.0.0.1:{self.manager_port}")


def end(pid: int) -> None:
    """SIGTERM, then SIGKILL if it is still there after LIMIT."""
    try:
        os.kill(pid, signal.SIGTERM)
    except ProcessLookupError:
        return
    deadline = time.monotonic() + LIMIT
    while live(pid) and time.monotonic() < deadline:
        time.sleep(0.02)
    if live(pid):
        os.kill(pid, signal.SIGKILL)


def run_demo(tmp_path: Path, config: Path = CONFIG) -> Iterator[Demo]:
    """A Demo of `config` (not started) with private ports, key and runtime directory; at
    the end its manager, daemon and processes are gone, whatever happened."""
    if not DAEMON.exists():
        pytest.fail(f"{DAEMON} is missing: run scons first")
    for exe in ("arm_sensor", "arm_controller"):
        if not (REPO / "build" / "release" / "examples" / "robot" / exe).exists():
            pytest.fail(f"examples/robot/{exe} is not built: run scons first")
    manager_port, daemon_port = free_port(), free_daemon_port()
    env = {**os.environ, "LN_RUNTIME_DIR": str(tmp_path / "run"),
           "LN_DAEMON_KEY_FILE": str(tmp_path / "key" / "daemon.key"),
           "LN_ARBITER_PORT": str(daemon_port), "LN_DEMO_PORT": str(manager_port),
           "LN_PYTHON": sys.executable}
    env.pop("LN_MANAGER", None)
    run = Demo(tmp_path, f"robot_demo_{uuid.uuid4().hex[:8]}", manager_port, daemon_port, env,
               config)
    try:
        yield run
    finally:
        if run.proc is not None:
            if run.proc.poll() is None:
                run.proc.send_signal(signal.SIGTERM)
                try:
                    run.proc.wait(timeout=LIMIT)
                except subprocess.TimeoutExpired:
                    run.proc.kill()
                    run.proc.wait()
            assert run.proc.stdout is not None
            run.proc.stdout.close()
        leftovers = run.demo_processes()
        for pid in run.daemon_pids():
            end(pid)
        for pid in leftovers:
            end(pid)
        assert run.daemon_pids() == []
        assert not leftovers, f"processes of the demo left running: {leftovers}"


@pytest.fixture
def demo(tmp_path: Path) -> Iterator[Demo]:
    yield from run_demo(tmp_path)


def first(history: list[dict[str, object]], state: str) -> float:
    return next(float(t["time"]) for t in history if t["state"] == state)  # type: ignore[arg-type]


def wait_for_output(mgr: Manager, name: str, pattern: re.Pattern[str]) -> list[str]:
    deadline = time.monotonic() + LIMIT
    while time.monotonic() < deadline:
        lines = mgr.output(name, 1000)
        if any(pattern.search(line) for line in lines):
            return lines
        time.sleep(0.1)
    pytest.fail(f"{name} printed no line matching {pattern.pattern!r} within {LIMIT} s:\n"
                + "\n".join(mgr.output(name, 1000)))


def test_robot_lnc_end_to_end(demo: Demo) -> None:
    demo.start()
    line = demo.stdout_line()
    assert f"instance {demo.instance} listening on 127.0.0.1:{demo.manager_port}" in line, \
        f"{line!r}\n{demo.log()}"
    line = demo.stdout_line()
    assert line.strip() == "ln_manager: all 3 processes ready", f"{line!r}\n{demo.log()}"

    with connect(f"127.0.0.1:{demo.manager_port}", timeout=LIMIT) as mgr:
        assert mgr.instance == demo.instance
        status = {p["name"]: p for p in mgr.status()}
        assert list(status) == ["arm/sensor", "arm/controller", "supervisor"]
        assert {n: p["state"] for n, p in status.items()} == dict.fromkeys(status, "ready")
        pids = [int(p["pid"]) for p in status.values()]
        assert all(live(pid) for pid in pids)
        assert sorted(demo.demo_processes()) == sorted(pids)

        # Dependency order: each one was spawned only once its dependency was ready.
        sensor = mgr.history("arm/sensor")
        controller = mgr.history("arm/controller")
        supervisor = mgr.history("supervisor")
        assert first(sensor, "ready") <= first(controller, "started")
        assert first(controller, "ready") <= first(supervisor, "started")
        assert "topic arm.state has a publisher" in sensor[-1]["reason"]
        assert "service arm.set_gains is registered" in controller[-1]["reason"]

        topics = {t["name"]: t for t in mgr.topics()}
        assert topics["arm.state"]["publishers"] == 1
        assert topics["arm.state"]["subscribers"] == 2  # controller and supervisor
        assert topics["arm.command"]["publishers"] == 1
        services = {s["name"]: s for s in mgr.services()}
        assert services["arm.set_gains"]["provider"] == "arm.controller"
        # the always-on logger of robot.lnc keeps every arm topic on the arm's host
        logged = wait_for(lambda: (t := mgr.command("logger_status", name="arm")["topics"])
                          and len(t) == 3 and all(x["stored"] > 0 for x in t) and t,
                          "the arm logger to hold samples")
        assert sorted(x["topic"] for x in logged) == ["arm.command", "arm.reference",
                                                      "arm.state"]

        # The supervisor's report: the tracking error, a refused setting, then stiffer gains.
        lines = wait_for_output(mgr, "supervisor", re.compile(r"tracking error .* 'stiff'"))
        assert lines[0] == "arm.set_gains 'soft': accepted"
        assert any(TRACKING.match(line) for line in lines), lines
        assert ("arm.set_gains 'unsafe': refused (kp[0] = 5000 Nm/rad is outside (0, 1000])"
                in lines)
        assert "arm.set_gains 'stiff': accepted" in lines
        sensor_out = mgr.output("arm/sensor", 1000)
        assert any(re.match(r"t=\d+ s, cycle \d+: \d+ commands in the last second", line)
                   for line in sensor_out), sensor_out

        mgr.quit()
    assert demo.proc is not None
    assert demo.proc.wait(timeout=LIMIT) == 0, demo.log()

    # Everything of the demo is gone: its processes (each exited by itself on SIGTERM) and
    # the instance's segments.  Only the daemon is left; the fixture ends it.
    assert not [pid for pid in pids if live(pid)]
    assert demo.demo_processes() == []
    assert segments(demo.instance) == []
    log = demo.log()
    for name in ("arm/sensor", "arm/controller", "supervisor"):
        assert re.search(rf"process {re.escape(name)}: stopped \(.*exit status 0\)", log), log
    assert demo.daemon_pids(), "the manager did not start its own ln_daemon"
