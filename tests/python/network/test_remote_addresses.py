"""LN_MANAGER for what the manager runs on other hosts: a process's and a state's commands
(check, up, down) on another node get the manager's address as that node reaches it
(runner.py sets Scheduler.manager_address_for for configurations spanning hosts), never
the manager's own loopback address.  On the scheduler's fake daemon."""

from __future__ import annotations

from pathlib import Path

from scheduler.fake_daemon import FakeDaemon, FakeRegistry, backend  # tests/python/scheduler

from links_and_nodes.manager.config import model
from links_and_nodes.manager.processes.scheduler import Scheduler

HERE = model.Location("test.lnc", 1, 1)
LOOPBACK = "127.0.0.1:54414"
FROM_B = "10.0.1.9:54414"


async def test_a_state_on_another_node_is_checked_with_the_managers_address_there(
        tmp_path: Path) -> None:
    seen = tmp_path / "seen"
    state = model.State("net", HERE, check=f'echo "$LN_MANAGER" >> {seen}', node="b")
    user = model.Process("user", HERE, "sleep 60", node="b", depends_on=["net"])
    cfg = model.Config(files=["test.lnc"], instance=model.Instance("t", ":54414", HERE),
                       processes={"user": user}, states={"net": state})
    daemon = FakeDaemon()
    sched = Scheduler(cfg, FakeRegistry(), backend(daemon), manager_address=LOOPBACK,
                      manager_address_for=lambda node: FROM_B if node == "b" else LOOPBACK)
    try:
        sched.start("user")
        await sched.wait_ready("user", 60)
        assert sched.states["net"].up
        assert seen.read_text().split() == [FROM_B]
    finally:
        await sched.close()
        await daemon.kill_all()
