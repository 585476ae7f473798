"""Starting an ln_daemon: which executable (a wheel's, the checkout's build, else PATH), probing
whether one listens, and starting a local one in the background when none does."""

from __future__ import annotations

import asyncio
import contextlib
import os
import shutil
from pathlib import Path

from ... import bundled
from .daemon_wire import MAGIC, DaemonError, Msg

# ---- starting a daemon ----------------------------------------------------------------------


def daemon_executable() -> str:
    """$LN_DAEMON, else the one a wheel carries in the package, else the release build of
    this checkout, else `ln_daemon` from PATH."""
    env = os.environ.get("LN_DAEMON")
    if env:
        return env
    in_package = bundled.program("ln_daemon")
    if in_package is not None:
        return str(in_package)
    in_tree = Path(__file__).resolve().parents[4] / "build" / "release" / "ln_daemon" / "ln_daemon"
    if os.access(in_tree, os.X_OK):
        return str(in_tree)
    return shutil.which("ln_daemon") or "ln_daemon"


async def _probe(host: str, port: int, timeout: float) -> bool:
    """True if an ln_daemon answers on host:port, False if nothing listens; DaemonError if
    something else does."""
    try:
        reader, writer = await asyncio.wait_for(asyncio.open_connection(host, port), timeout)
    except (TimeoutError, OSError):
        return False
    try:
        head = await asyncio.wait_for(reader.readexactly(4 + 5 + len(MAGIC)), timeout)
    except (TimeoutError, OSError, asyncio.IncompleteReadError):
        head = b""
    finally:
        writer.close()
        with contextlib.suppress(OSError):
            await writer.wait_closed()
    if head[4:5] != bytes([Msg.DAEMON_HELLO]) or head[9:] != MAGIC:
        raise DaemonError(f"{host}:{port} is in use by something that is not ln_daemon")
    return True


async def ensure_local_daemon(port: int, key_file: Path, log_file: Path | None = None,
                              timeout: float = 10.0, *, data_port: int | None = None) -> None:
    """Make sure an ln_daemon listens on 127.0.0.1:`port`: if none answers, start one with
    `key_file` (and `log_file`, and `data_port` for forwarding: None is the daemon's
    default, port + 1; 0 a free one) in its own session, so it outlives the caller, and
    return once it accepts connections.  DaemonError with the daemon's message if it cannot
    start."""
    loop = asyncio.get_running_loop()
    deadline = loop.time() + timeout
    if await _probe("127.0.0.1", port, timeout):
        return
    args = [daemon_executable(), "--port", str(port), "--key-file", os.fspath(key_file)]
    if log_file is not None:
        args += ["--log", os.fspath(log_file)]
    if data_port is not None:
        args += ["--data-port", str(data_port)]
    try:
        # Without --foreground the daemon detaches itself once it listens; this process
        # is only its launcher and ends at once with the start-up verdict.
        proc = await asyncio.create_subprocess_exec(
            *args, stdin=asyncio.subprocess.DEVNULL, stdout=asyncio.subprocess.DEVNULL,
            stderr=asyncio.subprocess.PIPE, start_new_session=True)
    except OSError as e:
        raise DaemonError(f"cannot run {args[0]}: {e.strerror}") from e
    try:
        _, err = await asyncio.wait_for(proc.communicate(), max(0.1, deadline - loop.time()))
    except TimeoutError:
        proc.kill()
        await proc.wait()
        raise DaemonError(f"ln_daemon did not start within {timeout} s") from None
    if proc.returncode != 0:
        # Another caller may have won the race for the port.
        if await _probe("127.0.0.1", port, max(0.1, deadline - loop.time())):
            return
        message = err.decode(errors="replace").strip() or f"exit status {proc.returncode}"
        raise DaemonError(f"ln_daemon did not start: {message}")
    while not await _probe("127.0.0.1", port, max(0.1, deadline - loop.time())):
        if loop.time() > deadline:
            raise DaemonError(f"ln_daemon started but does not accept on port {port}")
        await asyncio.sleep(0.05)
