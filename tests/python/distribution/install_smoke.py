"""The smoke test of a links_and_nodes that pip installed into a FreshVenv (from the wheel or
the sdist): the package uses its own libln, libln_admin.so, ln_daemon, message definitions and
uPlot, never the checkout's; ln_generate and the bundled headers and library build a C
publisher; `ln_manager -c` runs it beside a Python subscriber/publisher/service provider
until both are ready; `ln_manager topic echo` reads both topics and `service call` reaches the
provider; `quit` ends it.  Ports, instance, daemon key and runtime directory are private."""

from __future__ import annotations

import contextlib
import json
import os
import re
import shlex
import shutil
import signal
import subprocess
import time
import uuid
from pathlib import Path

from buildtree import REPO
from fresh_venv import LIMIT, FreshVenv, outside_checkout
from polling import free_daemon_port, free_port

HERE = Path(__file__).resolve().parent
WHERE = """
import json
import links_and_nodes, ln_generate
from links_and_nodes import _adminlib, _libln, _pull_lib
from links_and_nodes.manager.frontends.webui.assets import vendor_dir
from links_and_nodes.manager.processes.daemon_launch import daemon_executable
from ln_generate.lookup import builtin_md_dir
maps = [line.split()[-1] for line in open("/proc/self/maps") if ".so" in line]
print(json.dumps({
    "package": links_and_nodes.__file__, "ln_generate": ln_generate.__file__,
    "libln": next(p for p in maps if "/libln.so" in p),
    "libln_pull": next(p for p in maps if "/libln_pull.so" in p),
    "libln_admin": next(p for p in maps if "/libln_admin.so" in p),
    "ln_daemon": daemon_executable(), "message_definitions": str(builtin_md_dir()),
    "uplot": str(vendor_dir())}))
"""


def check_where(venv: FreshVenv) -> None:
    """Everything the package loads or starts lies in the venv."""
    where = json.loads(venv.run(venv.python, "-c", WHERE))
    outside_checkout(where)
    site = str(venv.root.resolve())
    elsewhere = {k: v for k, v in where.items() if not str(Path(v).resolve()).startswith(site)}
    assert not elsewhere, f"not from the venv {site}: {elsewhere}"


def build_publisher(venv: FreshVenv) -> Path:
    """tests/installed/publisher.c, with its header from ln_generate, against the package's
    headers and libln (python -m links_and_nodes.bundled --cflags --libs)."""
    shutil.copy(REPO / "tests" / "installed" / "publisher.c", venv.work)
    venv.run("ln_generate", "-o", "messages.h", "robot/joint_state")
    flags = shlex.split(venv.run(venv.python, "-m", "links_and_nodes.bundled", "--cflags",
                                 "--libs"))
    venv.run("cc", "-std=c11", "-Wall", "-Wextra", "-Werror", "-o", "publisher", "publisher.c",
             *flags)
    libln = re.search(r"libln\.so\.1 => (\S+)", venv.run("ldd", "publisher"))
    assert libln, "publisher is not linked to libln.so.1"
    assert Path(libln.group(1)).resolve().is_relative_to(venv.root.resolve()), libln.group(1)
    return venv.work / "publisher"


def write_config(venv: FreshVenv, publisher: Path, instance: str, port: int) -> Path:
    shutil.copy(HERE / "smoke_node.py", venv.work)
    lnc = venv.work / "smoke.lnc"
    lnc.write_text(f"""instance
name: {instance}
manager: :{port}

process publisher
    command: {publisher} 100000000
    ready_on_topic: smoke.state
    term_timeout: 2

process node
    command: {venv.python} {venv.work / 'smoke_node.py'}
    depends_on: publisher
    ready_on_service: smoke.set_gains
    term_timeout: 2
""")
    return lnc


def wait_for_text(path: Path, text: str, proc: subprocess.Popen[bytes]) -> str:
    deadline = time.monotonic() + LIMIT
    while text not in (log := path.read_text(errors="replace")):
        assert proc.poll() is None, f"ln_manager ended before '{text}':\n{log}"
        assert time.monotonic() < deadline, f"no '{text}' after {LIMIT} s:\n{log}"
        time.sleep(0.1)
    return log


def stop_daemon(runtime: Path, daemon_port: int) -> None:
    """End the ln_daemon the manager started (it outlives the manager by design)."""
    log = runtime / f"ln_daemon-{daemon_port}.log"
    text = log.read_text(errors="replace") if log.exists() else ""
    for pid in {int(p) for p in re.findall(r"ln_daemon\[(\d+)\]: listening on", text)}:
        try:
            Path(f"/proc/{pid}/cmdline").read_bytes().index(str(daemon_port).encode())
        except (OSError, ValueError):
            continue  # ended already, or the pid is no longer our daemon
        with contextlib.suppress(ProcessLookupError):
            os.kill(pid, signal.SIGTERM)


def run_system(venv: FreshVenv, installed_at: float) -> float:
    """ln_manager -c on the two-process config; the seconds from `installed_at` (the start
    of `pip install`) until `topic echo` printed the C publisher's first sample."""
    check_where(venv)
    publisher = build_publisher(venv)
    port, daemon_port = free_port(), free_daemon_port()
    instance = f"smoke_{uuid.uuid4().hex[:8]}"
    lnc = write_config(venv, publisher, instance, port)
    runtime = venv.work / "run"
    env = {**venv.env, "LN_RUNTIME_DIR": str(runtime), "LN_ARBITER_PORT": str(daemon_port),
           "LN_DAEMON_KEY_FILE": str(venv.work / "daemon.key")}
    log = venv.work / "manager.log"
    with open(log, "wb") as out:
        manager = subprocess.Popen(
            ["ln_manager", "-c", str(lnc), "--instance", instance, "--start-all",
             "--wait-ready", "--ready-timeout", "60", "--exit-on-failure", "--no-console"],
            cwd=venv.work, env=env, stdin=subprocess.DEVNULL, stdout=out,
            stderr=subprocess.STDOUT)
    try:
        text = wait_for_text(log, "processes ready", manager)
        assert "not all processes ready" not in text, text
        at = ["--manager", f"127.0.0.1:{port}"]
        state = venv.run("ln_manager", "topic", "echo", "smoke.state", "-n", "1", *at, env=env)
        first_topic = time.monotonic() - installed_at
        assert "position" in state and "cycle" in state, state
        echo = venv.run("ln_manager", "topic", "echo", "smoke.echo", "-n", "1", *at, env=env)
        assert "position" in echo, echo
        reply = venv.run("ln_manager", "service", "call", "smoke.set_gains",
                         'kp: [1, 2, 3, 4, 5, 6, 7], kd: [1, 1, 1, 1, 1, 1, 1], '
                         'profile_name: "wheel"', *at, env=env)
        seen = re.search(r"wheel: (\d+) samples seen", reply)
        assert seen and int(seen.group(1)) > 0, reply
        venv.run("ln_manager", "quit", *at, env=env)
        assert manager.wait(timeout=LIMIT) == 0, log.read_text(errors="replace")
    finally:
        if manager.poll() is None:
            manager.send_signal(signal.SIGTERM)
            manager.wait(timeout=LIMIT)
        stop_daemon(runtime, daemon_port)
    return first_topic


def uninstall_leaves_nothing(venv: FreshVenv, before: set[str]) -> None:
    """`pip uninstall` removes every file it lists, and the venv holds what it held before
    the package was installed."""
    listed = venv.installed_files("links_and_nodes")
    assert any(p.name == "libln.so.1" for p in listed), "libln.so.1 is not in the RECORD"
    venv.pip("uninstall", "-y", "links_and_nodes")
    left = [str(p) for p in listed if p.exists()]
    assert not left, f"left behind: {left}"
    stray = sorted(venv.files() - before)
    assert not stray, f"stray files in the venv: {stray}"
