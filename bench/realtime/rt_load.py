"""What runs beside bench/realtime's measurements: stress-ng loading CPU, memory and I/O, and
the links_and_nodes machinery a robot has running anyway — a manager with its web UI, started
with a configuration (so it starts the local ln_daemon, which keeps a topic logger of the
benchmark's topics), `ln_record` recording them, and a WebSocket scope on the web UI.  Each
part says why it is missing instead of failing the run."""

from __future__ import annotations

import os
import shutil
import signal
import socket
import subprocess
import sys
import time
import uuid
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from links_and_nodes.manager.frontends.launch import ManagerProcess, segments, start_manager
from links_and_nodes.manager.processes.daemon_keys import create_key_file
from links_and_nodes.manager.processes.daemon_launch import daemon_executable

HERE = Path(__file__).resolve().parent
MD_DIR = HERE.parent / "md"  # lnbench/sample_64; robot/* are in message_definitions/
# --cpu N: N busy workers (all stressors); --vm: a worker that keeps writing 256 MiB;
# --io: a worker calling sync(); --timer: 10 kHz of timer interrupts on top.
STRESS = ["--cpu", "2", "--vm", "1", "--vm-bytes", "256M", "--io", "1",
          "--timer", "1", "--timer-freq", "10000"]
PREFIX = "rtb"  # every benchmark topic starts with it: the logger and ln_record take rtb.*


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def lnc_text(instance: str, port: int) -> str:
    """The background's configuration: the web UI on, one idle process (which has the
    manager start and connect the local daemon), and a logger of every benchmark topic
    kept by that daemon (docs/logging.md)."""
    return f"""# written by bench/realtime/bench_realtime.py: the background of the measurement
instance
name: {instance}
manager: :{port}
webui: on

add_message_definition_dir: {MD_DIR}

process idle
    command: sleep 100000

logger rt
autostart: true
{PREFIX}.*: depth:10000
"""


@dataclass
class Background:
    """The processes that load the machine; `parts` says which run and why others do not."""

    tmp: Path
    parts: dict[str, str] = field(default_factory=dict)
    manager: ManagerProcess | None = None
    procs: dict[str, subprocess.Popen[bytes]] = field(default_factory=dict)
    logs: dict[str, Path] = field(default_factory=dict)

    @property
    def env(self) -> dict[str, str]:
        assert self.manager is not None
        return self.manager.env

    def start_manager(self) -> None:
        instance = f"rtbench{os.getpid()}x{uuid.uuid4().hex[:8]}"
        lnc = self.tmp / "background.lnc"
        lnc.write_text(lnc_text(instance, free_port()))
        self.start_daemon()
        self.manager = start_manager(instance, self.tmp / "runtime", self.tmp / "manager.log",
                                     "-c", str(lnc), "--no-console", "--start-all", "--webui",
                                     "--log-level", "warning")
        self.parts["manager"] = f"running ({self.manager.address}, web UI on)"
        self.parts["ln_daemon"] = "running (private port; process 'idle', logger 'rt')"

    def start_daemon(self) -> None:
        """A private ln_daemon in the foreground (so it ends with the run), on a free port;
        the manager finds it there instead of starting a detached one."""
        key = self.tmp / "key" / "daemon.key"
        create_key_file(key)
        port = free_port()
        os.environ["LN_DAEMON_KEY_FILE"] = str(key)
        os.environ["LN_ARBITER_PORT"] = str(port)
        self._spawn("ln_daemon", [daemon_executable(), "--foreground", "--port", str(port),
                                  "--data-port", "0", "--key-file", str(key)], os.environ)
        deadline = time.monotonic() + 20
        while time.monotonic() < deadline:
            with socket.socket() as s:
                if s.connect_ex(("127.0.0.1", port)) == 0:
                    return
            time.sleep(0.05)
        raise RuntimeError(f"ln_daemon did not listen: {self.logs['ln_daemon'].read_text()}")

    def start_extras(self, topics: list[str], stress: bool) -> None:
        """ln_record, the scope and stress-ng (with `stress`)."""
        assert self.manager is not None
        rec = shutil.which("ln_record", path=str(Path(sys.executable).parent)) or \
            shutil.which("ln_record")
        if rec:
            self._spawn("ln_record", [rec, "-o", str(self.tmp / "recording"), "-e",
                                      rf"{PREFIX}\..*", "--manager", self.manager.address, "--md-dir", str(MD_DIR),
                                      "-q"])
        else:
            self.parts["ln_record"] = "not installed"
        try:
            import websockets  # noqa: F401
        except ImportError:
            self.parts["scope"] = "missing: the websockets package is not installed"
        else:
            url = f"http://{self.manager.address}/"
            self._spawn("scope", [sys.executable, str(HERE / "rt_scope.py"), url, *topics])
        if not stress:
            self.parts["stress-ng"] = "off (--no-stress)"
        elif shutil.which("stress-ng") is None:
            self.parts["stress-ng"] = "not installed (apt-get install stress-ng)"
        else:
            self._spawn("stress-ng", ["stress-ng", *STRESS, "--temp-path", str(self.tmp)])

    def _spawn(self, name: str, argv: list[str], env: Any = None) -> None:
        log = self.tmp / f"{name}.log"
        self.logs[name] = log
        with open(log, "wb") as out:
            self.procs[name] = subprocess.Popen(argv, stdout=out, stderr=subprocess.STDOUT,
                                                env=env or self.env, start_new_session=True)
        self.parts[name] = "running: " + " ".join(STRESS) if name == "stress-ng" else "running"

    def alive(self) -> dict[str, bool]:
        """Which background processes still ran at the end of the measurement."""
        return {name: p.poll() is None for name, p in self.procs.items()}

    def stop(self) -> dict[str, Any]:
        """End everything (the daemon last); what the scope received, what was recorded and
        what the manager left behind."""
        done: dict[str, Any] = {"alive_at_end": self.alive()}
        for name in [n for n in self.procs if n != "ln_daemon"]:
            self._end(name)
        scope = self.logs.get("scope")
        if scope and scope.exists():
            lines = scope.read_text(errors="replace").strip().splitlines()
            done["scope"] = lines[-1] if lines else ""
        recording = self.tmp / "recording"
        done["recorded_bytes"] = sum(f.stat().st_size for f in recording.glob("*")
                                     ) if recording.exists() else 0
        if self.manager is not None:
            self.manager.stop()
            left = segments(self.manager.instance)
            for name in left:
                Path("/dev/shm", name).unlink(missing_ok=True)
            done["leftover_segments"] = left
        if "ln_daemon" in self.procs:
            self._end("ln_daemon")
        return done

    def _end(self, name: str) -> None:
        proc = self.procs[name]
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGINT if name == "stress-ng" else signal.SIGTERM)
        try:
            proc.wait(timeout=20)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
