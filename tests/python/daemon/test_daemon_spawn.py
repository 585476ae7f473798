"""SPAWN: the environment, working directory, resource limits, CPU affinity and scheduling
a process gets are exactly the ones asked for, and every way a start can fail comes back
as an error of SPAWN with a precise text, never as a silent exit."""

from __future__ import annotations

import asyncio
import os
import pwd
import resource
import shutil
import sys
import tempfile
import time
from pathlib import Path

import pytest
from daemonproc import PATH_ENV, Daemon, exited, spec, start_daemon, stop_daemon

from links_and_nodes.manager.processes import daemon_wire as dw

PY = sys.executable


def output_of(daemon: Daemon, s: dw.SpawnSpec) -> tuple[list[str], dw.Exited]:
    async def main() -> tuple[list[str], dw.Exited]:
        async with await daemon.connect() as client:
            await client.spawn(s)
            lines: list[str] = []
            return lines, await exited(client, s.name, lines)

    return asyncio.run(main())


def test_environment_is_exactly_the_given_one(daemon: Daemon) -> None:
    """... and LN_HOST_ID, the daemon's host id, unless the environment has one."""
    env = {**PATH_ENV, "FOO": "bar baz", "EMPTY": ""}
    s = dw.SpawnSpec("env", "env", False, env, use_pty=False)
    lines, ex = output_of(daemon, s)
    assert ex.exit_code == 0

    async def host_id() -> str:
        async with await daemon.connect() as client:
            return (await client.net_info()).host_id

    with_id = {**env, "LN_HOST_ID": asyncio.run(host_id())}
    assert sorted(lines) == sorted(f"{k}={v}" for k, v in with_id.items())


def test_environment_bytes_that_are_not_utf8_pass_unchanged(daemon: Daemon) -> None:
    """os.environ holds such bytes as lone surrogates (surrogateescape); the child gets the
    original bytes, as from a shell."""
    raw = os.fsdecode(b"a\xffb")
    code = "import os; print(os.environb[b'RAW'].hex())"
    s = dw.SpawnSpec("raw", f"{PY} -c \"{code}\"", False, {**PATH_ENV, "RAW": raw},
                     use_pty=False)
    lines, ex = output_of(daemon, s)
    assert ex.exit_code == 0
    assert lines == ["61ff62"]


def test_working_directory(daemon: Daemon, tmp_path: Path) -> None:
    lines, _ = output_of(daemon, spec("pwd", "pwd", shell=False, cwd=str(tmp_path)))
    assert lines == [str(tmp_path)]
    lines, _ = output_of(daemon, spec("root", "pwd", shell=False))
    assert lines == ["/"]  # no cwd: the root directory


def test_resource_limits(daemon: Daemon) -> None:
    s = spec("limits", "ulimit -Sn; ulimit -Hn; ulimit -Sc; ulimit -Hc",
             rlimits=[("nofile", 64, 128), ("RLIMIT_CORE", None, None)])
    lines, _ = output_of(daemon, s)
    assert lines == ["64", "128", "unlimited", "unlimited"]
    # Without a limit given, a process gets the descriptor limit the daemon started with
    # (the daemon raises its own).
    soft = resource.getrlimit(resource.RLIMIT_NOFILE)[0]
    lines, _ = output_of(daemon, spec("default", "ulimit -Sn"))
    assert lines == ["unlimited" if soft == resource.RLIM_INFINITY else str(soft)]


def test_cpu_affinity(daemon: Daemon) -> None:
    cpus = sorted(os.sched_getaffinity(0))
    for cpu in (cpus[0], cpus[-1]):
        s = spec(f"aff{cpu}", f"{PY} -c 'import os; print(sorted(os.sched_getaffinity(0)))'",
                 affinity=[cpu])
        lines, _ = output_of(daemon, s)
        assert lines == [str([cpu])]


@pytest.mark.skipif(os.geteuid() != 0, reason="real-time scheduling needs root here")
def test_sched_fifo(daemon: Daemon) -> None:
    code = ("import os; print(os.sched_getscheduler(0) == os.SCHED_FIFO, "
            "os.sched_getparam(0).sched_priority)")
    lines, _ = output_of(daemon, spec("fifo", f"{PY} -c '{code}'", policy="SCHED_FIFO",
                                      priority=10))
    assert lines == ["True 10"]
    code = "import os; print(os.sched_getscheduler(0) == os.SCHED_RR)"
    lines, _ = output_of(daemon, spec("rr", f"{PY} -c '{code}'", policy="rr", priority=1))
    assert lines == ["True"]


def test_nice_value(daemon: Daemon) -> None:
    code = "import os; print(os.getpriority(os.PRIO_PROCESS, 0))"
    lines, _ = output_of(daemon, spec("nice", f"{PY} -c '{code}'", priority=7))
    assert lines == ["7"]


def spawn_error(daemon: Daemon, s: dw.SpawnSpec) -> dw.DaemonError:
    async def main() -> dw.DaemonError:
        async with await daemon.connect() as client:
            with pytest.raises(dw.DaemonError) as info:
                await client.spawn(s)
            assert [p.name for p in await client.list()] == []  # nothing left of it
            await client.ping()  # the connection stays usable
            return info.value

    return asyncio.run(main())


def test_priority_out_of_range_is_refused(daemon: Daemon) -> None:
    err = spawn_error(daemon, spec("hi", "true", policy="SCHED_FIFO", priority=150))
    assert err.code == dw.ErrorCode.INVALID_SPEC
    assert str(err) == "priority 150 is out of range for SCHED_FIFO (1..99)"
    err = spawn_error(daemon, spec("nice", "true", priority=40))
    assert str(err) == "nice value 40 is out of range for SCHED_OTHER (-20..19)"
    err = spawn_error(daemon, spec("pol", "true", policy="SCHED_SOMETHING"))
    assert str(err).startswith("unknown scheduling policy 'SCHED_SOMETHING'")


def test_nonexistent_cpu_is_refused_by_the_kernel(daemon: Daemon) -> None:
    err = spawn_error(daemon, spec("cpu", "true", affinity=[1000]))
    assert err.code == dw.ErrorCode.SPAWN_FAILED
    assert str(err) == "cannot set CPU affinity to [1000]: Invalid argument"


@pytest.mark.skipif(os.geteuid() != 0, reason="needs root to run a daemon as another user")
def test_not_permitted_policy_is_a_clear_error() -> None:
    # A daemon running as an unprivileged user may not use SCHED_FIFO: the kernel's refusal
    # must come back as the SPAWN error.
    nobody = pwd.getpwnam("nobody")
    tmp = Path(tempfile.mkdtemp(prefix="ln_daemon_nobody."))
    try:
        os.chown(tmp, nobody.pw_uid, nobody.pw_gid)
        os.chmod(tmp, 0o700)
        daemon = start_daemon(tmp, user=nobody.pw_uid, group=nobody.pw_gid)
        try:
            err = spawn_error(daemon, spec("rt", "true", policy="SCHED_FIFO", priority=10))
            assert err.code == dw.ErrorCode.SPAWN_FAILED
            assert str(err).startswith("cannot set scheduling policy SCHED_FIFO with priority "
                                       "10: Operation not permitted (needs root")
            err = spawn_error(daemon, spec("neg", "true", priority=-5))
            assert str(err).startswith("cannot set nice value -5: Permission denied")
        finally:
            problems = stop_daemon(daemon)
        assert not problems, problems
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def test_command_not_found_is_a_spawn_error(daemon: Daemon, tmp_path: Path) -> None:
    err = spawn_error(daemon, spec("nf", "no-such-command-here --flag", shell=False))
    assert err.code == dw.ErrorCode.SPAWN_FAILED
    assert str(err) == "command not found: no-such-command-here"
    # The command is looked up in the PATH of the given environment, not the daemon's.
    err = spawn_error(daemon, dw.SpawnSpec("nopath", "ls", False, {"PATH": str(tmp_path)}))
    assert str(err) == "command not found: ls"


def test_exec_and_setup_failures(daemon: Daemon, tmp_path: Path) -> None:
    script = tmp_path / "not-executable"
    script.write_text("#!/bin/sh\n")
    err = spawn_error(daemon, spec("noexec", str(script), shell=False))
    assert str(err) == f"cannot execute '{script}': Permission denied"
    err = spawn_error(daemon, spec("nodir", "true", cwd=str(tmp_path / "missing")))
    assert str(err) == f"cannot change directory to '{tmp_path / 'missing'}': " \
                       "No such file or directory"
    err = spawn_error(daemon, spec("rel", "true", cwd="relative"))
    assert err.code == dw.ErrorCode.INVALID_SPEC
    err = spawn_error(daemon, spec("lim", "true", rlimits=[("nofile", 10, 5)]))
    assert str(err) == "resource limit nofile: soft limit 10 is above the hard limit 5"
    err = spawn_error(daemon, spec("log", "true",
                                   output_log=(str(tmp_path / "no" / "dir" / "log"), 0, 0)))
    assert str(err).startswith(f"cannot open output log '{tmp_path / 'no' / 'dir' / 'log'}'")


def test_shell_command_not_found_is_exit_127(daemon: Daemon) -> None:
    # With shell=True the shell itself starts fine; it reports the missing command.
    lines, ex = output_of(daemon, spec("sh", "no-such-command-here"))
    assert ex.exit_code == 127
    assert any("not found" in text for text in lines)


def test_spawned_info_and_name_in_use(daemon: Daemon) -> None:
    async def main() -> None:
        async with await daemon.connect() as client:
            info = await client.spawn(spec("s", "sleep 60"))
            assert info.state == "running" and info.pid > 0
            assert info.exit_code is None and info.signal is None
            assert info.started <= time.time()
            with pytest.raises(dw.DaemonError) as e:
                await client.spawn(spec("s", "true"))
            assert e.value.code == dw.ErrorCode.ALREADY_RUNNING
            assert str(e.value) == f"process s is already running (pid {info.pid})"
            await client.stop("s")
            await exited(client, "s")
            again = await client.spawn(spec("s", "true"))  # an exited name can be reused
            assert again.pid != info.pid
            await exited(client, "s")

    asyncio.run(main())
