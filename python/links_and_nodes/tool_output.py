"""One line of a command-line tool's output on stderr, whole even when threads say at once.

`print(text, file=sys.stderr)` writes the text and its newline separately, so two threads of a
bridge could glue their messages into one line; `say_line` writes each line in one piece.
"""

from __future__ import annotations

import sys
import threading

_lock = threading.Lock()


def say_line(prog: str, text: str) -> None:
    """`prog: text` as one line on stderr, flushed."""
    line = f"{prog}: {text}\n"
    with _lock:
        sys.stderr.write(line)
        sys.stderr.flush()
