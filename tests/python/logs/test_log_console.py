"""`log` in the console of `ln_manager -c FILE`: the collected lines with a filter, then
`log -f` printing each new line that passes it until the next command line."""

from __future__ import annotations

import os
import subprocess
import uuid
from pathlib import Path

from console_manager import console_manager
from polling import free_daemon_port, free_port

from .conftest import LIMIT, LOG_TOOL


def test_log_and_follow_in_the_console(tmp_path: Path) -> None:
    instance = f"lc{os.getpid()}x{uuid.uuid4().hex[:8]}"
    port, daemon_port = free_port(), free_daemon_port()
    config = tmp_path / "logs.lnc"
    config.write_text(f"instance\nname: {instance}\nmanager: 127.0.0.1:{port}\n\n")
    env = {**os.environ, "LN_RUNTIME_DIR": str(tmp_path / "run"),
           "LN_DAEMON_KEY_FILE": str(tmp_path / "daemon.key"),
           "LN_ARBITER_PORT": str(daemon_port), "PYTHONUNBUFFERED": "1"}
    with console_manager(config, instance, port, daemon_port, env, LIMIT) as con:
        tool_env = {**env, "LN_MANAGER": con.address}

        def levels(name: str) -> None:
            done = subprocess.run([str(LOG_TOOL), "levels", name], capture_output=True,
                                  text=True, env=tool_env, timeout=LIMIT)
            assert done.returncode == 0, done

        levels("first")
        con.send("log --level critical")
        [line] = con.expect(lambda line: "CRITICAL" in line, "the critical line")[-1:]
        assert "first@" in line and "c line at level 50: ok" in line
        con.send("log -f --level error --process second")
        levels("second")
        con.expect(lambda line: "ERROR" in line and "second@" in line, "a followed error")
        con.expect(lambda line: "CRITICAL" in line and "second@" in line, "a followed one")
        con.send("status")  # ends the following
        levels("third")
        con.send("log -n 1 --process third")
        last = con.expect(lambda line: "third@" in line, "the last line of third")
        assert not any("second@" in line and "WARNING" in line for line in con.seen)
        assert "c line without a place" in last[-1]
