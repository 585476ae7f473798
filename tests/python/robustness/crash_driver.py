"""Crash-injection driver: runs a synthetic system (publishers, subscribers, providers, callers
of crash_node.py) under a real `ln_manager -c` and ln_daemon, SIGKILLs a random component N
times with a fixed seed and checks after each kill that nothing hung, nothing was torn and
everything recovered, and after the final shutdown that nothing of the instance is left.

    python tests/python/robustness/crash_driver.py --count 200 --seed 1 [--small]
        [--two-hosts] [--kinds publisher,daemon,...] [--work DIR]

docs/robustness.md ("Crash injection") describes the system, the checks and the results.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import random
import signal
import subprocess
import sys
import time
import uuid
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

REPO = Path(__file__).resolve().parents[3]
for _p in (REPO / "python", REPO, REPO / "tests" / "python"):
    if str(_p) not in sys.path:
        sys.path.insert(0, str(_p))

from polling import free_daemon_port, free_port, pids_with  # noqa: E402

from links_and_nodes.manager.frontends.launch import segments  # noqa: E402
from links_and_nodes.tools import scripting  # noqa: E402

if TYPE_CHECKING:
    from netlab import DaemonProc, NetLab

NODE = Path(__file__).with_name("crash_node.py")
MD_DIRS = os.pathsep.join(str(REPO / "tests" / "fixtures" / "md" / d)
                          for d in ("topics", "services"))
KINDS = ("publisher", "subscriber", "provider", "caller", "manager", "daemon")
WEIGHTS = {"publisher": 4, "subscriber": 4, "provider": 3, "caller": 3, "manager": 1,
           "daemon": 1}
ROLE_OF = {"publisher": "pub", "subscriber": "sub", "provider": "provider", "caller": "caller"}
HANG = 8.0  # seconds without a heartbeat from a live process that count as a hang
RECOVER = 60.0  # seconds the system may take to be all-ready and flowing again
BUSY_WAIT = 3.0  # seconds to wait for a target to be inside a loan, borrow or handler
LAB_PORTS = (54414, 54376)  # manager and daemons in --two-hosts: each host has its own stack


@dataclass(frozen=True)
class Node:
    """One process of the system: its role (crash_node.py), mode and topics or services."""

    name: str
    role: str
    mode: str
    items: tuple[str, ...]


def design(processes: int, topics: int, services: int) -> list[Node]:
    """Publishers, subscribers, providers and callers in the ratio 3:3:2:2; every topic has
    one publisher and two subscribers, every service one provider and every caller calls
    every service."""
    n_pub = max(1, processes * 3 // 10)
    n_sub = max(2, processes * 3 // 10)
    n_prov = max(1, processes // 5)
    n_call = max(1, processes - n_pub - n_sub - n_prov)
    tnames = [f"crash.t{i:02d}" for i in range(topics)]
    snames = [f"crash.s{i:02d}" for i in range(services)]
    nodes: list[Node] = []
    pub_modes, sub_modes = ("copy", "loan"), ("latest", "queued", "borrow")
    for i in range(n_pub):
        nodes.append(Node(f"pub{i}", "pub", pub_modes[i % 2], tuple(tnames[i::n_pub])))
    for i in range(n_sub):
        mine = [t for k, t in enumerate(tnames) if k % n_sub in (i, (i + 1) % n_sub)]
        nodes.append(Node(f"sub{i}", "sub", sub_modes[i % 3], tuple(mine)))
    for i in range(n_prov):
        nodes.append(Node(f"prov{i}", "provider", "", tuple(snames[i::n_prov])))
    for i in range(n_call):
        nodes.append(Node(f"call{i}", "caller", "", tuple(snames)))
    return nodes


def alive(pid: int) -> bool:
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return False
    return stat.rsplit(")", 1)[1].split()[0] != "Z"


@dataclass
class Result:
    kills: list[dict[str, Any]] = field(default_factory=list)
    problems: list[str] = field(default_factory=list)
    segments_after_recovery: list[int] = field(default_factory=list)
    leftovers: list[str] = field(default_factory=list)
    calls: dict[str, float] = field(default_factory=dict)
    seconds: float = 0.0

    def kinds(self) -> set[str]:
        return {k["kind"] for k in self.kills}


class System:
    """The instance: its configuration, manager, daemon and the report files of its nodes."""

    def __init__(self, work: Path, nodes: list[Node], log: Callable[[str], None],
                 lab: NetLab | None = None) -> None:
        self.work = work
        self.nodes = nodes
        self.log = log
        self.lab = lab
        self.instance = f"crash-{os.getpid()}-{uuid.uuid4().hex[:8]}"
        self.reports = work / "reports"
        self.reports.mkdir(parents=True, exist_ok=True)
        self.runtime = work / "run"
        self.daemons: dict[str, DaemonProc] = {}
        # with a lab: the processes alternate between hosts a and b, the manager runs on a
        self.node_host = {node.name: "ab"[i % 2] if lab else "localhost"
                          for i, node in enumerate(nodes)}
        if lab is None:
            self.port, self.daemon_port = free_port(), free_daemon_port()
            self.host = "127.0.0.1"
            base = dict(os.environ)
        else:
            self.port, self.daemon_port = LAB_PORTS
            self.host = lab["a"].address
            base = {**lab["a"].env(), "PYTHONPATH": os.pathsep.join(
                [str(REPO / "python"), str(REPO)])}
        # with a lab the manager keeps the default runtime directory of host a
        runtime = {} if lab else {"LN_RUNTIME_DIR": str(self.runtime)}
        self.env = {**base, **runtime,
                    "LN_DAEMON_KEY_FILE": str(lab.key_file if lab else
                                              work / "keys" / "daemon.key"),
                    "LN_ARBITER_PORT": str(self.daemon_port), "PYTHONUNBUFFERED": "1"}
        self.config = work / "crash.lnc"
        self.config.write_text(self.lnc())
        self.managers: list[subprocess.Popen[bytes]] = []
        self.mgr: scripting.Manager | None = None

    def lnc(self) -> str:
        pythonpath = os.pathsep.join([str(REPO / "python"), str(REPO)])
        parts = [f"instance\nname: {self.instance}\nmanager: {self.address}\n\n"]
        if self.lab is not None:
            parts.append("hosts\n" + "".join(f"{h}: eth0: {self.lab[h].address}\n"
                                              for h in "ab") + "\n")
        for node in self.nodes:
            mode = f" --mode {node.mode}" if node.mode else ""
            parts.append(
                f"process {node.name}\n"
                f"node: {self.node_host[node.name]}\n"
                f"command: {sys.executable} {NODE} {node.role} {node.name} {self.reports} "
                f"{MD_DIRS} {','.join(node.items)}{mode}\n"
                f"environment: PYTHONPATH={pythonpath}\n"
                "ready_regex: ^ready\nrestart: always\nrestart_delay: 0.2\n"
                "restart_limit: 100000\nterm_timeout: 2\n\n")
        return "".join(parts)

    @property
    def address(self) -> str:
        return f"{self.host}:{self.port}"

    # ---- manager and daemon ----------------------------------------------------------------
    def start_daemons(self) -> None:
        """--two-hosts: the daemon of each host, as a system service would run it (the
        manager starts only a daemon of its own host by itself)."""
        if self.lab is not None:
            for h in "ab":
                self.daemons[h] = self.lab[h].start_daemon(self.lab.key_file,
                                                           port=self.daemon_port)

    def start_manager(self, *args: str) -> None:
        argv = [sys.executable, "-m", "links_and_nodes.manager", "-c", str(self.config),
                "--no-console", *args]
        name = f"manager-{len(self.managers)}.log"
        proc: subprocess.Popen[Any]
        if self.lab is not None:
            proc = self.lab["a"].popen(argv, env=self.env, log=f"../{name}")
        else:
            with open(self.work / name, "wb") as log:
                proc = subprocess.Popen(argv, stdin=subprocess.DEVNULL, stdout=log,
                                        stderr=log, env=self.env)
        self.managers.append(proc)
        self.mgr = None
        deadline = time.monotonic() + RECOVER
        while time.monotonic() < deadline:
            if proc.poll() is not None:
                raise RuntimeError(f"ln_manager exited with {proc.returncode}:\n"
                                   f"{self.manager_log()}")
            with contextlib.suppress(scripting.ManagerError):
                self.mgr = self.connect()
                return
            time.sleep(0.05)
        raise RuntimeError("ln_manager did not listen in time")

    def manager_log(self) -> str:
        path = self.work / f"manager-{len(self.managers) - 1}.log"
        if not path.exists():
            return ""
        return path.read_text(errors="replace")[-4000:]

    def control(self) -> scripting.Manager:
        """The scripting connection, made again if the manager connection broke."""
        if self.mgr is None:
            self.mgr = self.connect()
        return self.mgr

    def connect(self) -> scripting.Manager:
        def connect() -> scripting.Manager:
            return scripting.connect(self.address, timeout=10.0)

        if self.lab is None:
            return connect()
        from netlab import in_netns

        return in_netns(self.lab["a"].netns, connect)

    def segments(self) -> list[str]:
        """The instance's segments in /dev/shm here and, with a lab, in each host's."""
        found = segments(self.instance)
        if self.lab is not None:
            prefix = f"ln.{self.instance}."
            for h in "ab":
                found += [f"{h}:{name}" for name in os.listdir(self.lab[h].path("/dev/shm"))
                          if name.startswith(prefix)]
        return found

    def runtime_dirs(self) -> list[Path]:
        if self.lab is None:
            return [self.runtime]
        # the lab's hosts drop LN_RUNTIME_DIR: libln's and the manager's default
        return [self.lab[h].path(f"/tmp/ln-{os.getuid()}/{self.instance}") for h in "ab"]

    def status(self) -> dict[str, dict[str, Any]]:
        try:
            return {p["name"]: p for p in self.control().status()}
        except scripting.ManagerError:
            if self.mgr is not None:
                self.mgr.close()
            self.mgr = None
            raise

    def daemon_pids(self) -> list[int]:
        """The instance's ln_daemon(s), not their keepers: those share its command line, are
        named ln_daemon-keep and may outlive a killed daemon for a moment."""
        if self.lab is not None:
            return [d.pid for d in self.daemons.values() if d.running()]
        found = []
        for pid in pids_with(f"--port\0{self.daemon_port}\0".encode()):
            with contextlib.suppress(OSError):
                if Path(f"/proc/{pid}/comm").read_text().strip() == "ln_daemon":
                    found.append(pid)
        return found

    def heartbeat(self, name: str) -> dict[str, Any] | None:
        try:
            return json.loads((self.reports / f"{name}.hb").read_text())  # type: ignore[no-any-return]
        except (OSError, ValueError):
            return None

    def new_violations(self, seen: dict[str, int]) -> list[str]:
        """Lines of the NAME.violations files beyond the `seen` count of each (updated)."""
        lines = []
        for path in sorted(self.reports.glob("*.violations")):
            mine = path.read_text().splitlines()
            lines += [f"{path.stem}: {line}" for line in mine[seen.get(path.name, 0):]]
            seen[path.name] = len(mine)
        return lines

    def busy(self, name: str) -> bool:
        return (self.reports / f"{name}.busy").exists()

    def shutdown(self) -> None:
        """quit, then end the daemon (the manager started it and leaves it running)."""
        with contextlib.suppress(scripting.ManagerError):
            self.control().quit()
        for proc in self.managers:
            try:
                proc.wait(timeout=RECOVER)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
        if self.mgr is not None:
            self.mgr.close()
            self.mgr = None
        for daemon in self.daemons.values():
            daemon.terminate(timeout=RECOVER)
        for pid in [] if self.lab else self.daemon_pids():
            with contextlib.suppress(ProcessLookupError):
                os.kill(pid, signal.SIGTERM)

    def kill_everything(self) -> None:
        """Last resort after a failure: nothing of the instance may outlive the driver."""
        for proc in self.managers:
            if proc.poll() is None:
                proc.kill()
                proc.wait()
        for pid in pids_with(f"--port\0{self.daemon_port}\0".encode()) + \
                pids_with(str(self.reports).encode()):
            with contextlib.suppress(ProcessLookupError):
                os.kill(pid, signal.SIGKILL)


class Driver:
    def __init__(self, system: System, seed: int, log: Callable[[str], None]) -> None:
        self.sys = system
        self.rng = random.Random(seed)
        self.log = log
        self.result = Result()
        self.seen_violations: dict[str, int] = {}

    def problem(self, text: str) -> None:
        self.log(f"PROBLEM: {text}")
        self.result.problems.append(text)

    def pid_map(self) -> dict[str, int]:
        return {n: int(p["pid"] or 0) for n, p in self.sys.status().items()}

    def wait_recovered(self, before: dict[str, int], victims: set[str], kill: dict[str, Any]
                       ) -> None:
        """Until every process is ready with a fresh heartbeat of its current pid and every
        subscriber, caller and publisher made progress on every item; meanwhile every process
        that was not killed must keep its heartbeat going (no hang)."""
        start = time.monotonic()
        deadline = start + RECOVER
        nudged = False
        progress_from: dict[str, dict[str, float]] | None = None
        hung: set[str] = set()
        while True:
            now = time.time()
            for name, pid in before.items():
                if name in victims or name in hung or not alive(pid):
                    continue
                hb = self.sys.heartbeat(name)
                if hb is not None and hb["pid"] == pid and now - hb["time"] > HANG:
                    hung.add(name)
                    self.problem(f"after kill {kill['n']} ({kill['kind']} {kill['target']}): "
                                 f"{name} (pid {pid}) sent no heartbeat for "
                                 f"{now - hb['time']:.1f} s")
            try:
                status = self.sys.status()
            except scripting.ManagerError:
                status = {}
            ready = bool(status) and all(
                p["state"] == "ready" and p["pid"] and alive(int(p["pid"]))
                and (hb := self.sys.heartbeat(n)) is not None and hb["pid"] == p["pid"]
                and now - hb["time"] < HANG for n, p in status.items())
            if ready and progress_from is None:
                progress_from = {n: self.progress(n) for n in status}
                kill["ready_s"] = round(time.monotonic() - start, 2)
            if ready and progress_from is not None and all(
                    self.advanced(node, progress_from[node.name]) for node in self.sys.nodes):
                kill["flowing_s"] = round(time.monotonic() - start, 2)
                return
            if not ready:
                progress_from = None
            if status and not nudged and time.monotonic() - start > 10 and any(
                    p["state"] in ("failed", "stopped") for p in status.values()):
                # the restart policy did not bring it back: start it through the manager
                nudged = True
                kill["driver_started"] = sorted(n for n, p in status.items()
                                                if p["state"] in ("failed", "stopped"))
                with contextlib.suppress(scripting.ManagerError):
                    self.sys.control().start("all")
            if time.monotonic() > deadline:
                states = {n: (p["state"], p["reason"]) for n, p in status.items()
                          if p["state"] != "ready"}
                stuck = [node.name for node in self.sys.nodes if progress_from
                         and not self.advanced(node, progress_from[node.name])]
                self.problem(f"after kill {kill['n']} ({kill['kind']} {kill['target']}): not "
                             f"recovered in {RECOVER:.0f} s: not ready {states}; no progress "
                             f"{stuck}")
                return
            time.sleep(0.2)

    def progress(self, name: str) -> dict[str, float]:
        hb = self.sys.heartbeat(name) or {}
        what = {"pub": "sent", "sub": "good", "provider": "", "caller": "ok"}
        node = next(n for n in self.sys.nodes if n.name == name)
        key = what[node.role]
        counts = hb.get("counts", {})
        return {item: counts.get(item, {}).get(key, 0) for item in node.items} if key else {}

    def advanced(self, node: Node, before: dict[str, float]) -> bool:
        now = self.progress(node.name)
        return all(now[item] > before[item] or now[item] < before[item]  # restarted: reset
                   for item in before)

    def kill_one(self, n: int, kind: str) -> None:
        time.sleep(self.rng.uniform(0.0, 1.0))
        kill: dict[str, Any] = {"n": n, "kind": kind}
        before = self.pid_map()
        victims: set[str] = set()
        if kind == "manager":
            kill["target"] = "ln_manager"
            proc = self.sys.managers[-1]
            proc.send_signal(signal.SIGKILL)
            proc.wait()
            if self.sys.mgr is not None:
                self.sys.mgr.close()
                self.sys.mgr = None
            time.sleep(self.rng.uniform(0.0, 1.0))  # the system runs on without a manager
            self.sys.start_manager()
        elif kind == "daemon" and self.sys.lab is not None:
            host = self.rng.choice("ab")
            kill["target"] = f"ln_daemon on {host}"
            self.sys.daemons[host].kill()
            # its keepers end its processes; a service manager would start it again
            victims = {name for name in before if self.sys.node_host[name] == host}
            time.sleep(self.rng.uniform(0.0, 1.0))
            self.sys.daemons[host].start()
        elif kind == "daemon":
            kill["target"] = "ln_daemon"
            pids = self.sys.daemon_pids()
            if len(pids) != 1:
                self.problem(f"kill {n}: expected one ln_daemon, found {pids}")
            for pid in pids:
                os.kill(pid, signal.SIGKILL)
            victims = set(before)  # its keepers end every process
        else:
            node = self.rng.choice([x for x in self.sys.nodes if x.role == ROLE_OF[kind]])
            kill["target"] = node.name
            victims = {node.name}
            if node.mode in ("loan", "borrow") or node.role == "provider":
                deadline = time.monotonic() + BUSY_WAIT
                while not self.sys.busy(node.name) and time.monotonic() < deadline:
                    time.sleep(0.002)
                kill["mid_operation"] = self.sys.busy(node.name)
            os.kill(before[node.name], signal.SIGKILL)
        self.wait_recovered(before, victims, kill)
        self.log(f"kill {n}: {kind} {kill['target']}"
                 + (" (mid-operation)" if kill.get("mid_operation") else "")
                 + f"; ready after {kill.get('ready_s')} s, flowing after "
                   f"{kill.get('flowing_s')} s")
        with contextlib.suppress(scripting.ManagerError):
            after = self.pid_map()
            collateral = sorted(n for n in before if n not in victims and after[n] != before[n])
            if collateral:  # a kill must not take down anything but its target
                self.problem(f"kill {n} ({kind} {kill['target']}) also restarted "
                             f"{collateral}")
        for line in self.sys.new_violations(self.seen_violations):
            self.problem(f"after kill {n}: {line}")
        kill["segments"] = len(self.sys.segments())
        self.result.segments_after_recovery.append(kill["segments"])
        self.result.kills.append(kill)

    def plan(self, count: int, kinds: tuple[str, ...]) -> list[str]:
        """Every kind once (shuffled) first, then random kinds; processes more often."""
        first = list(kinds)
        self.rng.shuffle(first)
        weights = [WEIGHTS[k] for k in kinds]
        rest = self.rng.choices(kinds, weights=weights, k=max(0, count - len(first)))
        return (first + rest)[:count]


def leftover_files(runtime: Path) -> list[str]:
    """What the instance left in its runtime directory, but for the two files that stay by
    design: manager.lock (emptied; unlinking an flock file would race with the next
    manager) and the log of the ln_daemon the manager started (which outlives it)."""
    if not runtime.exists():
        return []
    return sorted(p.name for p in runtime.iterdir()
                  if not (p.name == "manager.lock" and p.stat().st_size == 0)
                  and not (p.name.startswith("ln_daemon-") and p.name.endswith(".log")))


def call_outcomes(reports: Path) -> dict[str, float]:
    """Over every caller's NAME.calls: calls answered, failed, and the longest one (s)."""
    ok = failed = 0
    longest = 0.0
    for path in reports.glob("*.calls"):
        for line in path.read_text().splitlines():
            parts = line.split()
            if len(parts) < 4:
                continue  # a line cut by the caller's kill
            ok += parts[2] == "ok"
            failed += parts[2] == "error"
            longest = max(longest, float(parts[-1]))
    return {"ok": ok, "failed": failed, "longest_s": longest}


def run(count: int, seed: int, work: Path, *, small: bool, two_hosts: bool = False,
        kinds: tuple[str, ...] = KINDS, log: Callable[[str], None] = print) -> Result:
    """The whole experiment; Result.problems is empty when every check held."""
    if not two_hosts:
        return _run(count, seed, work, small, None, kinds, log)
    from netlab import NetLab, require_netlab

    require_netlab()
    with NetLab(work / "netlab") as lab:
        return _run(count, seed, work, small, lab, kinds, log)


def _run(count: int, seed: int, work: Path, small: bool, lab: NetLab | None,
         kinds: tuple[str, ...], log: Callable[[str], None]) -> Result:
    started = time.monotonic()
    nodes = design(10, 12, 4) if small else design(20, 50, 10)
    system = System(work, nodes, log, lab)
    driver = Driver(system, seed, log)
    log(f"instance {system.instance}: {len(nodes)} processes, "
        f"{len({t for n in nodes if n.role == 'pub' for t in n.items})} topics, "
        f"{len({s for n in nodes if n.role == 'provider' for s in n.items})} services; "
        f"work directory {work}" + (", on hosts a and b" if lab else ""))
    try:
        system.start_daemons()
        system.start_manager("--start-all")
        driver.wait_recovered({}, set(), {"n": 0, "kind": "start", "target": "all"})
        if not driver.result.problems:
            for n, kind in enumerate(driver.plan(count, kinds), 1):
                driver.kill_one(n, kind)
                if any("not recovered" in p for p in driver.result.problems):
                    break  # the rest would only repeat it
        system.shutdown()
        for line in system.new_violations(driver.seen_violations):
            driver.problem(f"at the end: {line}")
        deadline = time.monotonic() + RECOVER
        while time.monotonic() < deadline and (
                pids_with(str(system.reports).encode()) or system.daemon_pids()
                or system.segments()):
            time.sleep(0.1)
        left = pids_with(str(system.reports).encode()) + system.daemon_pids()
        if left:
            driver.problem(f"processes left after the shutdown: {left}")
        driver.result.leftovers = system.segments() + [
            f"{d}/{name}" for d in system.runtime_dirs() for name in leftover_files(d)]
        if driver.result.leftovers:
            driver.problem(f"left after the shutdown: {driver.result.leftovers}")
    finally:
        system.kill_everything()
    driver.result.calls = call_outcomes(system.reports)
    driver.result.seconds = round(time.monotonic() - started, 1)
    return driver.result


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description="SIGKILL random components of a synthetic LN system and check that "
                    "nothing hangs, nothing is torn, everything recovers and nothing is left")
    parser.add_argument("--count", type=int, default=200, help="kills (default 200)")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--small", action="store_true",
                        help="10 processes, 12 topics, 4 services (the CI size) instead of "
                             "20, 50 and 10")
    parser.add_argument("--two-hosts", action="store_true",
                        help="processes on two emulated hosts (tests/python/netlab.py, root)")
    parser.add_argument("--kinds", help="comma-separated kinds to kill (default: all of "
                        f"{','.join(KINDS)}; with --two-hosts all but manager, see "
                        "docs/robustness.md, \"Crash injection\")")
    parser.add_argument("--work", type=Path, help="directory for the configuration, logs "
                        "and reports (default: a new one under /tmp)")
    args = parser.parse_args(argv)
    work = args.work or Path(f"/tmp/ln-crash-{os.getpid()}")
    work.mkdir(parents=True, exist_ok=True)
    if args.kinds:
        kinds = tuple(args.kinds.split(","))
        if not set(kinds) <= set(KINDS):
            parser.error(f"--kinds: choose from {', '.join(KINDS)}")
    else:
        kinds = tuple(k for k in KINDS if not (args.two_hosts and k == "manager"))
    result = run(args.count, args.seed, work, small=args.small, two_hosts=args.two_hosts,
                 kinds=kinds)
    summary = {"count": len(result.kills), "seed": args.seed, "seconds": result.seconds,
               "kinds": {k: sum(x["kind"] == k for x in result.kills) for k in kinds},
               "mid_operation": sum(bool(x.get("mid_operation")) for x in result.kills),
               "driver_started": sum("driver_started" in x for x in result.kills),
               "max_recovery_s": max((x.get("flowing_s", 0) for x in result.kills),
                                     default=0),
               "max_segments": max(result.segments_after_recovery, default=0),
               "calls": result.calls,
               "problems": result.problems}
    print(json.dumps(summary, indent=1))
    (work / "kills.json").write_text(json.dumps(result.kills, indent=1))
    return 1 if result.problems else 0


if __name__ == "__main__":
    sys.exit(main())
