"""Resource samples end to end (docs/process_management.md, "Resources and limits"): a real
manager and ln_daemon; a busy loop shows about a core of CPU, an allocation its RSS, the host
figures are there and sane, `ln_manager top --once/--json` prints them, and a process over
`max_rss` is flagged (a warning, the flag in status) and, with `on_limit: restart`,
restarted.  Figures are checked against broad bounds, never against the clock."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from typing import Any

from links_and_nodes.tools.scripting import Manager

from .conftest import LIMIT, Lab, wait_for

CHILD = Path(__file__).with_name("resource_child.py")
MIB = 1 << 20


def process(name: str, *args: str, marker: str, extra: str = "") -> str:
    words = " ".join([sys.executable, str(CHILD), *args, marker])
    return f"process {name}\ncommand: {words}\nready_regex: ready\n{extra}\n\n"


def start(lab: Lab, body: str) -> Manager:
    proc = lab.manager(lab.write(body), "--no-console")
    lab.wait_listening(proc)
    return lab.connect()


def row(mgr: Manager, name: str) -> dict[str, Any]:
    return next(p for p in mgr.resources()["processes"] if p["name"] == name)


def test_busy_loop_cpu_allocation_rss_and_host(lab: Lab) -> None:
    m = lab.instance
    body = process("busy", "busy", marker=m) + process("mem", "alloc", "64", marker=m)
    with start(lab, body) as mgr:
        mgr.start("all")
        mgr.wait_ready("all", LIMIT)
        # a busy loop shows more than half a core in some sample (the machine is shared)
        wait_for(lambda: (row(mgr, "busy")["cpu"] or 0) > 50, "busy at > 50 % CPU", LIMIT)
        wait_for(lambda: (row(mgr, "mem")["rss"] or 0) >= 64 * MIB, "mem's RSS >= 64 MiB",
                 LIMIT)
        mem = row(mgr, "mem")
        assert mem["threads"] >= 1 and mem["fds"] >= 3
        assert mem["ctx_voluntary"] >= 0 and mem["ctx_involuntary"] >= 0
        assert mem["limit"] == ""
        result = mgr.resources()
        (host,) = result["hosts"]
        assert host["cpus"] and all(0 <= c <= 100 for c in host["cpus"])
        assert 0 <= host["cpu"] <= 100
        assert 0 < host["mem_available"] <= host["mem_total"]
        assert all(x >= 0 for x in host["load"])
        assert any(n["interface"] == "lo" for n in host["nets"])
        assert result["signals"]["process/mem/rss"] >= 64 * MIB
        assert f"host/{host['host']}/cpu" in result["signals"]
        status = {p["name"]: p for p in mgr.status()}
        assert status["mem"]["rss"] >= 64 * MIB and status["busy"]["threads"] >= 1
        # the CLI: once as tables, once as JSON
        cli = [sys.executable, "-m", "links_and_nodes.manager", "top", "--manager",
               f"127.0.0.1:{lab.manager_port}"]
        out = subprocess.run([*cli, "--once"], capture_output=True, text=True, env=lab.env,
                             timeout=LIMIT, check=True).stdout
        lines = out.splitlines()
        assert lines[0].split()[:3] == ["host", "load", "cpu"]
        assert any(line.split()[:2] == ["mem", "ready"] for line in lines)
        out = subprocess.run([*cli, "--json"], capture_output=True, text=True, env=lab.env,
                             timeout=LIMIT, check=True).stdout
        data = json.loads(out)
        assert {p["name"] for p in data["processes"]} == {"busy", "mem"}


def test_max_rss_flags_a_process(lab: Lab) -> None:
    m = lab.instance
    body = process("mem", "alloc", "48", marker=m, extra="max_rss: 16M")
    with start(lab, body) as mgr:
        mgr.start("mem")
        mgr.wait_ready("mem", LIMIT)
        flagged = wait_for(lambda: next(p for p in mgr.status() if p["name"] == "mem")["limit"],
                           "the max_rss flag", LIMIT)
        assert "max_rss 16.0 MiB" in str(flagged)
        assert next(p for p in mgr.status() if p["name"] == "mem")["state"] == "ready"
        wait_for(lambda: "process mem: over its limit: RSS" in lab.log(), "the warning", LIMIT)


def test_max_rss_with_on_limit_restart(lab: Lab) -> None:
    m = lab.instance
    body = process("mem", "alloc", "48", marker=m,
                   extra="max_rss: 16M\non_limit: restart\nrestart_delay: 0.1")
    with start(lab, body) as mgr:
        mgr.start("mem")

        def restarted() -> bool:
            history = mgr.history("mem")
            failed = [t for t in history if t["state"] == "failed"
                      and "over its limit: RSS" in str(t["reason"])]
            return bool(failed) and any(t["state"] == "starting"
                                        for t in history[history.index(failed[0]):])
        wait_for(restarted, "a restart after max_rss", LIMIT)
