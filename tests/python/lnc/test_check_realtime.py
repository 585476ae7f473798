"""`ln_manager check` warns where a requested real-time policy cannot be applied on this host
(frontends/check_realtime.py): RLIMIT_RTPRIO below the priority and no CAP_SYS_NICE, at the
`priority` (else `policy`) key, only for processes on the manager's host; and the same
through a real `ln_manager check` whose RLIMIT_RTPRIO is lowered (and, as root, CAP_SYS_NICE
dropped) before it starts."""

from __future__ import annotations

import os
import resource
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

from links_and_nodes.manager.frontends import check_realtime as rt

from .helpers import cfg, load_files, loc, write

ROBOT = cfg("""
    process arm
        command: /bin/true
        policy: SCHED_FIFO
        priority: 80
    process logger
        command: /bin/true
        policy: SCHED_RR
        priority: 10
    process gui
        command: /bin/true
        priority: -5
    process remote
        command: /bin/true
        node: robot-pc
        policy: FIFO
        priority: 90
    """)

NO_RT = rt.HostLimits(rtprio=0, cap_sys_nice=False)


def test_warns_at_the_priority_key_for_local_processes_only(tmp_path: Path) -> None:
    config = load_files(tmp_path, {"robot.lnc": ROBOT})
    main = tmp_path / "robot.lnc"
    found = rt.realtime_warnings(config, "lab-pc", NO_RT)
    assert [(p.location, p.message.split(":", 1)[0]) for p in found] == [
        (loc(main, 7, 15), "process 'arm'"), (loc(main, 11, 15), "process 'logger'")]
    assert "SCHED_FIFO with priority 80 cannot be applied on this host: RLIMIT_RTPRIO is 0 " \
           "(below 80) and CAP_SYS_NICE is not effective" in found[0].message


def test_no_warning_when_the_limit_or_the_capability_allows_it(tmp_path: Path) -> None:
    config = load_files(tmp_path, {"robot.lnc": ROBOT})
    assert rt.realtime_warnings(config, "lab-pc", rt.HostLimits(80, False)) == []
    assert rt.realtime_warnings(config, "lab-pc", rt.HostLimits(None, False)) == []
    assert rt.realtime_warnings(config, "lab-pc", rt.HostLimits(0, True)) == []
    # between the two priorities: only the higher one is refused
    found = rt.realtime_warnings(config, "lab-pc", rt.HostLimits(50, None))
    assert [p.message.split(":", 1)[0] for p in found] == ["process 'arm'"]
    assert "RLIMIT_RTPRIO is 50 (below 80)" in found[0].message


def test_the_manager_host_by_name_is_checked_too(tmp_path: Path) -> None:
    config = load_files(tmp_path, {"robot.lnc": ROBOT})
    found = rt.realtime_warnings(config, "robot-pc", NO_RT)
    assert [p.message.split(":", 1)[0] for p in found] == [
        "process 'arm'", "process 'logger'", "process 'remote'"]


def test_capability_bit_of_proc_status() -> None:
    assert rt.cap_effective("Name:\tx\nCapEff:\t0000000000800000\n", 23) is True
    assert rt.cap_effective("CapEff:\t000001fffe7fffff\n", 23) is False
    assert rt.cap_effective("Name:\tx\n", 23) is None


def check_argv(main: Path, *extra: str) -> list[str]:
    """`ln_manager check MAIN EXTRA...`, run without CAP_SYS_NICE when run as root (setpriv,
    else capsh)."""
    argv = [sys.executable, "-m", "links_and_nodes.manager", "check", str(main), *extra]
    if os.geteuid() != 0:
        return argv
    if shutil.which("setpriv"):
        return ["setpriv", "--inh-caps=-sys_nice", "--bounding-set=-sys_nice", "--", *argv]
    assert shutil.which("capsh"), "as root the test needs setpriv or capsh to drop CAP_SYS_NICE"
    return ["capsh", "--drop=cap_sys_nice", "--", "-c", shlex.join(argv)]


def run_lowered(argv: list[str]) -> subprocess.CompletedProcess[str]:
    """Run `argv` with RLIMIT_RTPRIO lowered to 0 (soft and hard) before it starts."""

    def lower() -> None:
        resource.setrlimit(resource.RLIMIT_RTPRIO, (0, 0))

    return subprocess.run(argv, capture_output=True, text=True, timeout=60,
                          stdin=subprocess.DEVNULL, preexec_fn=lower)


def test_a_real_check_with_rtprio_lowered_warns(tmp_path: Path) -> None:
    main = write(tmp_path, {"robot.lnc": ROBOT})
    r = run_lowered(check_argv(main))
    assert r.returncode == 0, r.stderr
    lines = r.stderr.splitlines()
    assert lines[0].startswith(f"{main}:7:15: warning: process 'arm': SCHED_FIFO with "
                               "priority 80 cannot be applied on this host: RLIMIT_RTPRIO is 0")
    assert lines[1].startswith(f"{main}:11:15: warning: process 'logger': SCHED_RR")
    assert lines[-1] == f"ln_manager check: {main}: ok (4 processes, 2 warnings)"
    strict = run_lowered(check_argv(main, "--strict"))
    assert strict.returncode == 1
    assert strict.stderr.splitlines()[0].startswith(f"{main}:7:15: process 'arm': SCHED_FIFO")
    assert strict.stderr.splitlines()[0].endswith("[warning, an error with --strict]")
