"""Client logging end to end (docs/logging.md, "Client logging"): lines at each level from C
(ln_log, LN_LOG), C++ (client.log) and Python (ln.LogHandler) arrive at the manager with their
level, time, client, host, file:line and text; the filters of `log` (scripting API and
`ln_manager log`); a flood from one client drops with a count and blocks neither the client
nor the manager."""

from __future__ import annotations

import logging
import queue
import signal
import subprocess
import sys
import threading
import time
import uuid

import links_and_nodes as ln
from links_and_nodes.tools import scripting

from .conftest import LIMIT, LOG_TOOL, LOG_TOOL_CPP, Manager, printed_lines, run_tool

LEVELS = (10, 20, 30, 40, 50)


def _entries(mgr: scripting.Manager, **filters: object) -> list[dict[str, object]]:
    return list(mgr.log(**{"n": 20000, **filters}))


def test_c_lines_arrive_with_their_fields(manager: Manager,
                                          scripted: scripting.Manager) -> None:
    name = f"logc{uuid.uuid4().hex[:6]}"
    before = time.time()
    places = printed_lines(run_tool(manager, LOG_TOOL, "levels", name))
    after = time.time()
    got = _entries(scripted, process=name)
    assert [e["level"] for e in got] == [*LEVELS, 20]
    hosts = {e["host"] for e in got}
    assert len(hosts) == 1 and "" not in hosts
    for e in got[:5]:
        level = int(e["level"])  # type: ignore[call-overload]
        assert e["client"] == name and e["source"] == "client" and int(e["pid"]) > 0
        assert str(e["file"]).endswith("tests/c/tools/log_tool.c")
        assert e["line"] == places[level]
        assert e["text"] == f"c line at level {level}: ok"
        assert e["level_name"] == {10: "debug", 20: "info", 30: "warning", 40: "error",
                                   50: "critical"}[level]
        assert before - 1 <= float(e["time"]) <= after + 1  # type: ignore[arg-type]
    assert got[5]["file"] == "" and got[5]["line"] == 0
    assert got[5]["text"] == "c line without a place"


def test_cpp_lines_arrive_with_the_callers_place(manager: Manager,
                                                 scripted: scripting.Manager) -> None:
    name = f"logcpp{uuid.uuid4().hex[:6]}"
    places = printed_lines(run_tool(manager, LOG_TOOL_CPP, name))
    got = _entries(scripted, process=name)
    assert [e["level"] for e in got] == list(LEVELS)
    for e in got:
        assert str(e["file"]).endswith("tests/c/tools/log_tool_cpp.cpp")
        assert e["line"] == places[int(e["level"])]  # type: ignore[call-overload]
        assert e["text"] == f"c++ line at level {e['level']}"


def test_python_handler_sends_records(manager: Manager,
                                      scripted: scripting.Manager) -> None:
    name = f"logpy{uuid.uuid4().hex[:6]}"
    clnt = ln.client(name, manager.address)
    logger = logging.getLogger(f"robot.{name}")
    logger.setLevel(logging.DEBUG)
    logger.propagate = False
    handler = ln.LogHandler(clnt)
    logger.addHandler(handler)
    try:
        lines = {}
        for level in LEVELS:
            lines[level] = sys._getframe().f_lineno + 1
            logger.log(level, "py line %d", level)
        handler.flush(LIMIT)
        got = _entries(scripted, process=name)
        assert [e["level"] for e in got] == list(LEVELS)
        for e in got:
            assert e["file"] == __file__ and e["line"] == lines[int(e["level"])]  # type: ignore[call-overload]
            assert e["logger"] == f"robot.{name}" and e["text"] == f"py line {e['level']}"
        assert handler.queued == 5 and handler.dropped == 0
    finally:
        logger.removeHandler(handler)
        clnt.close()


def test_filters_of_the_scripting_api_and_the_cli(manager: Manager,
                                                  scripted: scripting.Manager) -> None:
    a, b = f"fa{uuid.uuid4().hex[:6]}", f"fb{uuid.uuid4().hex[:6]}"
    run_tool(manager, LOG_TOOL, "levels", a)
    run_tool(manager, LOG_TOOL_CPP, b)
    everything = _entries(scripted)
    assert {e["client"] for e in everything} == {a, b}
    warnings = _entries(scripted, level="warning")
    assert sorted(int(e["level"]) for e in warnings) == [30, 30, 40, 40, 50, 50]  # type: ignore[call-overload]
    assert {e["client"] for e in _entries(scripted, process="fb*")} == {b}
    assert [e["text"] for e in _entries(scripted, grep="C++ LINE AT LEVEL 4")] == \
        ["c++ line at level 40"]
    host = everything[0]["host"]
    assert len(_entries(scripted, host=str(host))) == len(everything)
    assert _entries(scripted, host="no-such-host") == []
    assert len(_entries(scripted, n=3)) == 3
    last = everything[-1]["seq"]
    assert _entries(scripted, since=last) == []
    done = subprocess.run([sys.executable, "-m", "links_and_nodes.manager", "log", "--manager",
                           manager.address, "--level", "error", "--process", a],
                          capture_output=True, text=True, timeout=LIMIT)
    assert done.returncode == 0, done.stderr
    shown = done.stdout.splitlines()
    assert len(shown) == 2 and "ERROR" in shown[0] and "CRITICAL" in shown[1]
    assert all(f"{a}@{host} " in line and "log_tool.c:" in line for line in shown)
    bad = subprocess.run([sys.executable, "-m", "links_and_nodes.manager", "log", "--manager",
                          manager.address, "--level", "loud"],
                         capture_output=True, text=True, timeout=LIMIT)
    assert bad.returncode != 0 and "unknown log level 'loud'" in bad.stderr


def test_flood_drops_with_a_count_and_blocks_nobody(manager: Manager,
                                                    scripted: scripting.Manager) -> None:
    n = 100_000
    lines = run_tool(manager, LOG_TOOL, "flood", str(n))  # bounded by LIMIT: it completes
    words = lines[0].split()
    assert words[0] == "done" and int(words[1]) == n
    queued, dropped, eagain = int(words[3]), int(words[5]), int(words[7])
    assert queued + eagain == n
    assert eagain > 0 and dropped >= eagain  # the queue (1,024 lines) overflowed, counted
    status = scripted.status()  # the manager still answers
    assert status == []
    result = scripted.command("log", process="log_flood", n=0)
    assert {"client": "log_flood", "host": _entries(scripted, n=1)[0]["host"],
            "dropped": dropped} in result["dropped"]
    arrived = len(_entries(scripted, process="log_flood")) + result["evicted"]
    assert arrived == queued - (dropped - eagain)


def test_cli_follow_streams_new_lines(manager: Manager) -> None:
    follower = subprocess.Popen([sys.executable, "-m", "links_and_nodes.manager", "log", "-f",
                                 "--manager", manager.address, "--level", "error"],
                                stdout=subprocess.PIPE, text=True)
    manager.tools.append(follower)  # type: ignore[arg-type]
    try:
        name = f"follow{uuid.uuid4().hex[:6]}"
        run_tool(manager, LOG_TOOL, "levels", name)  # logged after the follower started
        assert follower.stdout is not None
        lines: queue.Queue[str] = queue.Queue()
        threading.Thread(target=lambda: [lines.put(line) for line in follower.stdout],
                         daemon=True).start()
        shown = [lines.get(timeout=LIMIT), lines.get(timeout=LIMIT)]  # bounds a hang only
        assert "ERROR" in shown[0] and "CRITICAL" in shown[1]
        assert all(f"{name}@" in line and "log_tool.c:" in line for line in shown)
    finally:
        follower.send_signal(signal.SIGINT)
        assert follower.wait(timeout=LIMIT) == 0
