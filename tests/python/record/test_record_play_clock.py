"""The replay clock of `ln_play --clock`: a Python client (client.now()) and a C or C++
program (ln_now / client.now(), tests/c/tools/clock_tool*.c*) follow it: 0 before the first clock sample, standing
still while paused (equal values, the player's position), monotonic while playing at rate 2,
and jumping on a seek."""

from __future__ import annotations

import subprocess
from collections.abc import Iterator

import pytest
from buildtree import build_dir
from polling import wait_for

import links_and_nodes as ln

from .conftest import Lab
from .player_control import T0, Control, start_player, write_recording
from .recording import WAIT

SECOND = 1_000_000_000


class CClock:
    """clock_tool (C) or clock_tool_cpp: now() values on request."""

    def __init__(self, lab: Lab, tool_name: str) -> None:
        tool = build_dir() / "tests" / "c" / "tools" / tool_name
        self.proc = subprocess.Popen([str(tool), "-"], stdin=subprocess.PIPE,
                                     stdout=subprocess.PIPE, text=True, env=lab.env())
        lab.procs.append(self.proc)  # type: ignore[arg-type]
        assert self.proc.stdout is not None and self.proc.stdout.readline() == "ready\n"

    def now(self, n: int = 1) -> list[int]:
        assert self.proc.stdin is not None and self.proc.stdout is not None
        self.proc.stdin.write(f"now {n}\n")
        self.proc.stdin.flush()
        return [int(v) for v in self.proc.stdout.readline().split()]

    def close(self) -> None:
        assert self.proc.stdin is not None
        self.proc.stdin.close()
        assert self.proc.wait(timeout=WAIT) == 0


@pytest.fixture(params=["clock_tool", "clock_tool_cpp"])
def clients(lab: Lab, request: pytest.FixtureRequest) -> Iterator[tuple[ln.client, CClock]]:
    with lab.client("follower") as clnt:
        clnt.use_clock()
        cclock = CClock(lab, request.param)
        yield clnt, cclock
        cclock.close()


def monotonic_run(clnt: ln.client, cclock: CClock) -> tuple[list[int], list[int]]:
    py = [clnt.now() for _ in range(300)]
    c = cclock.now(300)
    assert py == sorted(py) and c == sorted(c)
    return py, c


def stands_at(clnt: ln.client, cclock: CClock, t_ns: int) -> None:
    """Both clocks show exactly t_ns, again and again."""
    wait_for(lambda: clnt.now() == t_ns, f"client.now() == {t_ns}")
    wait_for(lambda: cclock.now() == [t_ns], f"ln_now == {t_ns}")
    assert {clnt.now() for _ in range(100)} | set(cclock.now(100)) == {t_ns}


def test_now_follows_pause_rate_and_seek(lab: Lab, clients: tuple[ln.client, CClock]) -> None:
    clnt, cclock = clients
    assert clnt.now() == 0 and cclock.now() == [0]  # no clock sample yet
    path = lab.tmp / "clock.mcap"
    write_recording(path, 100, 10 * SECOND)  # 990 s: it does not end during the test
    proc, name = start_player(lab, path, "--start-paused", "--clock", "200")
    ctl = Control(clnt, name)
    stands_at(clnt, cclock, T0)

    ctl("set_rate", rate=2.0)
    ctl("resume")
    with lab.client("watch") as watcher:
        sub = watcher.subscribe("ln.clock", "ln/clock")
        msg = wait_for(lambda: (m := sub.read(timeout=WAIT)) is not None and not m.paused
                       and m.rate == 2.0 and m, "a playing clock sample at rate 2")
        assert msg.time_ns >= T0
    py, c = monotonic_run(clnt, cclock)
    assert py[0] >= T0 and c[0] >= T0
    wait_for(lambda: clnt.now() > py[-1] and cclock.now()[0] > c[-1], "the clock moving on")
    # a pause never stands ahead of what was published: on a loaded machine the clock can
    # move on before the player got to its first sample
    wait_for(lambda: ctl("status").played >= 1, "the first sample published")

    paused = ctl("pause")
    assert paused.state == "paused" and paused.position_ns > T0
    stands_at(clnt, cclock, paused.position_ns)

    target = T0 + 500 * SECOND
    assert ctl("seek", time_ns=target).position_ns == target
    stands_at(clnt, cclock, target)

    ctl("resume")
    wait_for(lambda: clnt.now() > target and cclock.now()[0] > target, "playing after 500 s")
    before = max(clnt.now(), *cclock.now())
    back = T0 + 100 * SECOND
    ctl("seek", time_ns=back)  # while playing: a jump back, then on from there
    wait_for(lambda: back <= clnt.now() < before and back <= cclock.now()[0] < before,
             "the jump back")
    py, c = monotonic_run(clnt, cclock)
    assert min(py + c) >= back and max(py + c) < before

    proc.terminate()
    assert proc.wait(timeout=WAIT) == 0


def test_use_clock_once_per_client(lab: Lab) -> None:
    with lab.client("follower") as clnt:
        before = clnt.now()
        assert before > 0  # CLOCK_REALTIME until use_clock
        clnt.use_clock("my.clock")
        clnt.use_clock("my.clock")  # the same: fine
        with pytest.raises(ln.LnExistError):
            clnt.use_clock()
        assert clnt.now() == 0
