"""The `parameters` key of a `process` section (docs/parameters.md, docs/configuration.md):
initial overrides of the process's parameter blocks, one `BLOCK.PARAM: VALUE` per line
(a `[` block for several; `add parameters:` extends).  VALUE is JSON or the flow style of
`ln_manager param set` (1.5, [1, 2, 3], "text", nan).  Checked here for syntax; the block
checks type and range when the process registers it, and says what it refused."""

from __future__ import annotations

import re
from typing import TYPE_CHECKING

from .drafts import KeyLine, ProcessDraft
from .errors import LineError
from .text import Value
from .values import fail

if TYPE_CHECKING:
    from .parser import Parser

_NAME = re.compile(r"([A-Za-z0-9_-]{1,63})\.([A-Za-z0-9_.-]{1,63})\Z")


def _entry(v: Value) -> tuple[str, str, object]:
    name, colon, text = v.text.partition(":")
    if not colon:
        raise fail(v, f"'parameters' takes BLOCK.PARAM: VALUE, got '{v.text}'")
    match = _NAME.match(name.strip())
    if match is None:
        raise fail(v, f"'{name.strip()}' is no BLOCK.PARAM (a block name of A-Z a-z 0-9 _ -, "
                      "a parameter name of A-Z a-z 0-9 _ . -)")
    if not text.strip():
        raise fail(v, f"'parameters': no value for {name.strip()}")
    from ...tools.parameters.values import ParamError, parse_value

    try:
        value = parse_value(text.strip())
    except ParamError as exc:
        raise fail(v, f"'parameters': {name.strip()}: {exc}", len(name) + 1) from None
    return match.group(1), match.group(2), value


def parameters_key(d: ProcessDraft, values: list[Value], p: Parser, kl: KeyLine) -> None:
    """Apply `parameters:` / `add parameters:` to the process being read."""
    entries, problems = [], []
    for v in values:
        if not v.text.strip():
            continue
        try:
            entries.append(_entry(v))
        except LineError as exc:
            problems.extend(exc.problems)
    if problems:
        raise LineError(problems)
    if not kl.add:
        d.process.parameters.clear()
    for block, param, value in entries:
        d.process.parameters.setdefault(block, {})[param] = value

