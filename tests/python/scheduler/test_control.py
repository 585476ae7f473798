"""Control requests and console lines with bad input are answered with an error and change
nothing; they never end the connection, the console or the manager."""

from __future__ import annotations

import asyncio
import io
import json
from collections.abc import AsyncIterator
from types import SimpleNamespace

import pytest

from links_and_nodes.manager.frontends.console import Console
from links_and_nodes.manager.frontends.control import Control
from links_and_nodes.manager.processes.scheduler import Scheduler
from links_and_nodes.manager.processes.states import ProcState as S
from links_and_nodes.tools import protocol as p
from links_and_nodes.tools.scripting import Manager, ManagerError

from .fake_daemon import FakeDaemon, FakeRegistry, backend
from .test_scheduler import LIMIT, config, proc


@pytest.fixture
async def control() -> AsyncIterator[Control]:
    daemon = FakeDaemon()
    sched = Scheduler(config(proc("a"), proc("keep", flags={"disable_stop"})), FakeRegistry(),
                      backend(daemon), manager_address="127.0.0.1:1")
    core = SimpleNamespace(registry=SimpleNamespace(topics={}), services=lambda: [])
    yield Control(core, sched)  # type: ignore[arg-type]
    await sched.close()
    await daemon.kill_all()


async def ask(control: Control, text: str) -> dict[str, object]:
    answer = json.loads(await asyncio.wait_for(control.handle_json(text), LIMIT))
    assert isinstance(answer, dict)
    return answer


@pytest.mark.parametrize("request_text", [
    '{"op": "output", "name": ["a"]}',
    '{"op": "history", "name": {"a": 1}}',
    '{"op": "output", "name": "a", "n": true}',
    '{"op": "wait_ready", "target": "a", "timeout": NaN}',
    '{"op": "wait_ready", "target": "a", "timeout": Infinity}',
    '{"op": "wait_ready", "target": "a", "timeout": true}',
    '{"op": "stop", "target": "keep", "force": "no"}',
    '{"op": "stop", "target": "keep", "force": 1}',
    "[" * 100000 + "]" * 100000,
    '{"op": "start", "target": 7}',
    '{"op": "status", "extra": ' + "[" * 50000 + "]" * 50000 + '}',
])
async def test_bad_requests_are_answered_with_an_error(control: Control,
                                                       request_text: str) -> None:
    answer = await ask(control, request_text)
    assert answer["ok"] is False and isinstance(answer["error"], str)
    assert control.scheduler is not None
    assert {p["name"]: p["state"] for p in control.scheduler.status()} == \
        {"a": "stopped", "keep": "stopped"}


async def test_an_internal_error_is_answered(control: Control,
                                             monkeypatch: pytest.MonkeyPatch) -> None:
    assert control.scheduler is not None

    def broken() -> list[dict[str, object]]:
        raise RuntimeError("something is broken")
    monkeypatch.setattr(control.scheduler, "status", broken)
    answer = await ask(control, '{"op": "status"}')
    assert answer == {"ok": False, "error": "internal error: something is broken"}


async def test_console_bad_lines_answer_errors(control: Control) -> None:
    out = io.StringIO()
    console = Console(control, out)
    for line in ["output a -n ²", "output a -n", "output", "start", "history", "'", "bogus"]:
        assert await console.execute(line) is False
    lines = out.getvalue().splitlines()
    assert len(lines) == 7 and all(text.startswith("error: ") for text in lines), lines


async def test_console_stops_following_when_it_ends(control: Control) -> None:
    assert control.scheduler is not None
    stream = asyncio.StreamReader()
    stream.feed_data(b"output a -f\n")
    console = Console(control, io.StringIO())
    task = asyncio.create_task(console.run(stream))
    await asyncio.wait_for(_until(lambda: bool(control.scheduler.output_listeners)), LIMIT)
    task.cancel()
    with pytest.raises(asyncio.CancelledError):
        await task
    assert control.scheduler.output_listeners == []
    assert control.scheduler.procs["a"].state == S.STOPPED


async def _until(predicate: object) -> None:
    while not predicate():  # type: ignore[operator]
        await asyncio.sleep(0.01)


@pytest.mark.parametrize("answer", ["not json", "[1, 2]", '"ok"', "{\"ok\": false}",
                                    '{"ok": false, "error": 7}'])
def test_scripting_turns_a_malformed_answer_into_manager_error(answer: str) -> None:
    """What `ln_manager status|...` prints as an error (exit status 1), not a traceback."""
    mgr = Manager.__new__(Manager)
    mgr.timeout, mgr._next_id = 1.0, 0
    mgr._send = lambda msg: None  # type: ignore[method-assign]
    mgr._receive = lambda timeout: p.ControlResult(1, answer)  # type: ignore[method-assign]
    with pytest.raises(ManagerError):
        mgr.command("status")


async def test_runner_starts_nothing_once_asked_to_stop(tmp_path: object) -> None:
    """SIGTERM while the manager attaches (which can take a while): --start-all does not
    start everything only to stop it again."""
    import argparse
    from pathlib import Path

    from links_and_nodes.manager.app import runner_for
    from links_and_nodes.manager.processes.daemons import DaemonPool

    args = argparse.Namespace(instance="t", daemon_key_file=None, exit_on_failure=False,
                              start_all=True, no_console=True, wait_ready=True,
                              ready_timeout=None)
    stopping = asyncio.Event()
    daemon = FakeDaemon()
    cfg = config(proc("a"))
    pool = DaemonPool(cfg, "t", log_dir=Path(str(tmp_path)))
    runner = runner_for(args, cfg, FakeRegistry(), pool, None,  # type: ignore[arg-type]
                        Path(str(tmp_path)), "127.0.0.1:1", lambda processes: stopping.set(),
                        stopping)
    runner.scheduler.backend = backend(daemon)
    stopping.set()
    try:
        assert await asyncio.wait_for(runner.begin(), LIMIT) == 0
        assert runner.scheduler.procs["a"].state == S.STOPPED
    finally:
        await runner.scheduler.close()
        await daemon.kill_all()
