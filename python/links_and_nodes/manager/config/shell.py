"""Runs the shell commands a `.lnc` file asks for while it is read (`%(shell CMD)` and
`pipe_include CMD`): `/bin/sh -c CMD` in the directory of the file, no stdin, a time
limit after which the command's whole process group is killed."""

from __future__ import annotations

import os
import signal
import subprocess
from collections.abc import Mapping

SHELL_TIMEOUT = 10.0  # seconds a command may run while a configuration is read


class CommandError(Exception):
    """The command could not run, failed or timed out; str() says which and why."""


def run_command(command: str, cwd: str, env: Mapping[str, str], timeout: float) -> str:
    """stdout of `command` (decoded as UTF-8, undecodable bytes kept as surrogates).
    Raises CommandError when it cannot start, exits non-zero or runs past `timeout`."""
    if not command.strip():
        raise CommandError("empty command")
    try:
        proc = subprocess.Popen(["/bin/sh", "-c", command], cwd=cwd or None, env=dict(env),
                                stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                                stderr=subprocess.PIPE, start_new_session=True)
    except OSError as exc:
        raise CommandError(f"command '{command}' could not be started: "
                           f"{exc.strerror or exc}") from None
    try:
        out, err = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        _kill_group(proc)
        raise CommandError(f"command '{command}' did not finish within {timeout:g} s "
                           "(killed)") from None
    finally:
        if proc.poll() is None:  # an exception other than the timeout
            _kill_group(proc)
    if proc.returncode != 0:
        status = (f"was killed by signal {-proc.returncode}" if proc.returncode < 0
                  else f"failed with exit status {proc.returncode}")
        detail = _last_line(err)
        raise CommandError(f"command '{command}' {status}" + (f": {detail}" if detail else ""))
    return out.decode("utf-8", "surrogateescape")


def _kill_group(proc: subprocess.Popen[bytes]) -> None:
    """The shell and everything it started: a grandchild holding stdout open would
    otherwise keep communicate() waiting."""
    try:
        os.killpg(proc.pid, signal.SIGKILL)
    except ProcessLookupError:
        pass
    proc.communicate()


def _last_line(data: bytes) -> str:
    lines = [line.strip() for line in data.decode("utf-8", "replace").splitlines()]
    lines = [line for line in lines if line]
    return lines[-1][:200] if lines else ""
