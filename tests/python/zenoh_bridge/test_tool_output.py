"""Lines the bridges and recorder tools say from several threads stay whole lines, also when
writing to stderr lets another thread run (a pipe or file that blocks for a moment)."""

from __future__ import annotations

import contextlib
import io
import threading
import time

from links_and_nodes.tool_output import say_line


class _SlowStream(io.StringIO):
    """A stream whose every write gives the other threads a turn, as a blocking write does."""

    def write(self, s: str) -> int:
        time.sleep(0.0001)
        return super().write(s)


def test_threads_saying_at_once_never_glue_lines() -> None:
    stream = _SlowStream()

    def say_many(who: str) -> None:
        for i in range(300):
            say_line("ln_tool", f"{who} line {i}")

    with contextlib.redirect_stderr(stream):
        threads = [threading.Thread(target=say_many, args=(f"t{n}",)) for n in range(4)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
    lines = stream.getvalue().splitlines()
    assert len(lines) == 1200
    bad = [line for line in lines if line.count("ln_tool: ") != 1]
    assert not bad, bad[:3]
    for n in range(4):
        assert [line for line in lines if line.startswith(f"ln_tool: t{n} ")] == [
            f"ln_tool: t{n} line {i}" for i in range(300)]
