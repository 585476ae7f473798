"""The static worst-case stack of the pull_mcu firmware, by scripts/stack-chain over the
call graphs GCC wrote for its build (-fcallgraph-info=su): the deepest chain from
Reset_Handler plus the deepest interrupt handler's chain plus the 36 bytes the core pushes on
an exception (8 registers and the alignment word; the handlers share one priority, so they
never nest).  The consumer's indirect calls (its send and data callbacks) are counted as the
deepest chain of the firmware's callbacks, on_send and on_data, measured the same way;
libgcc and libc helpers take the script's built-in bounds (--default-externs)."""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from buildtree import REPO

CORE = ("pull_dit", "pull_decode")  # libln_pull's sources in the firmware (firmware/SConscript)
ROOT = "Reset_Handler"
HANDLERS = ("SysTick_Handler", "UART0RX_Handler")
CALLBACKS = ("on_send", "on_data")
EXCEPTION_FRAME = 36


@dataclass
class StackBound:
    callbacks: int  # the budget of an indirect call
    main_chain: int  # bytes from Reset_Handler down its deepest chain
    handler_chain: int  # the deepest handler's chain with the exception frame
    total: int
    chain: list[str]  # the deepest chain from Reset_Handler


def _call_graphs(build: Path) -> list[str]:
    """The .ci files of the sources the firmware is built from now (not those an earlier
    build left of a source since removed)."""
    own = [build / f"{src.stem}.ci" for src in sorted((REPO / "firmware" / "pull_mcu").glob("*.c"))]
    core = [build / "ln_pull" / f"{name}.ci" for name in CORE]
    missing = [str(p) for p in own + core if not p.exists()]
    if missing:
        raise AssertionError(f"missing call graphs (run scons): {', '.join(missing)}")
    return [str(p) for p in own + core]


def _stack_chain(build: Path, roots: tuple[str, ...], *extra: str) -> dict[str, Any]:
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "stack.json"
        run = subprocess.run(
            [
                sys.executable,
                str(REPO / "scripts" / "stack-chain"),
                "--roots",
                ",".join(roots),
                *_call_graphs(build),
                "--default-externs",
                *extra,
                "--json",
                str(out),
            ],
            capture_output=True,
            text=True,
        )
        if run.returncode != 0:
            raise AssertionError(f"scripts/stack-chain failed:\n{run.stdout}{run.stderr}")
        return json.loads(out.read_text())  # type: ignore[no-any-return]


def firmware_stack_bound(build: Path) -> StackBound:
    budget = _stack_chain(build, CALLBACKS)["worst_bytes"]
    roots = _stack_chain(build, (ROOT, *HANDLERS), "--callback-budget", str(budget))["roots"]
    main = roots[ROOT]["bytes"]
    handler = max(roots[h]["bytes"] for h in HANDLERS) + EXCEPTION_FRAME
    return StackBound(budget, main, handler, main + handler, roots[ROOT]["chain"])
