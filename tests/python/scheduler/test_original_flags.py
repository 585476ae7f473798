"""Flags of the original Links and Nodes that change what the scheduler does:
no_error_on_stop, dont_stop_dependent_procs and forward_x11 (on the fake daemon)."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

from links_and_nodes.manager.processes.states import ProcState as S

from .test_scheduler import LIMIT, World, make, proc, until, world_factory  # noqa: F401


async def test_no_error_on_stop_makes_a_failing_exit_finished(
        world_factory: list[World]) -> None:  # noqa: F811
    w = make(world_factory, proc("lenient", "sh -c 'exit 3'", flags={"no_error_on_stop"}),
             proc("strict", "sh -c 'exit 3'"))
    w.sched.start("all")
    await w.sched.wait(["lenient"], {S.FINISHED}, LIMIT)
    await w.sched.wait(["strict"], {S.FAILED}, LIMIT)
    assert w.sched.procs["lenient"].reason == "exit status 3"


async def test_dont_stop_dependent_procs_keeps_dependents_running(
        world_factory: list[World]) -> None:  # noqa: F811
    w = make(world_factory, proc("a", flags={"dont_stop_dependent_procs"}),
             proc("b", depends_on=["a"]), proc("c"), proc("d", depends_on=["c"]))
    w.sched.start("all")
    await w.sched.wait_ready("all", LIMIT)
    await w.sched.stop("a")
    await w.sched.stop("c")
    assert w.sched.procs["a"].state == S.STOPPED
    assert w.sched.procs["b"].state == S.READY  # the flag: left running
    assert w.sched.procs["d"].state == S.STOPPED  # without it: stopped first
    assert ("b", S.STOPPING) not in w.log


async def test_forward_x11_passes_the_display(world_factory: list[World],  # noqa: F811
                                              tmp_path: Path,
                                              monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("DISPLAY", ":42")
    monkeypatch.setenv("XAUTHORITY", "/tmp/xauth-test")
    script = tmp_path / "env.py"
    script.write_text("import os\nprint('DISPLAY=' + os.environ.get('DISPLAY', '-'), "
                      "'XAUTHORITY=' + os.environ.get('XAUTHORITY', '-'), flush=True)\n")
    w = make(world_factory, proc("x", f"{sys.executable} {script}", flags={"forward_x11"}),
             proc("plain", f"{sys.executable} {script}"))
    w.sched.start("all")
    await w.sched.wait(["x", "plain"], {S.FINISHED}, LIMIT)

    def text(name: str) -> list[str]:
        return [line.text for line in w.sched.output(name)]

    await until(lambda: bool(text("x")) and bool(text("plain")))
    assert text("x") == ["DISPLAY=:42 XAUTHORITY=/tmp/xauth-test"]
    assert text("plain") == ["DISPLAY=- XAUTHORITY=-"]
