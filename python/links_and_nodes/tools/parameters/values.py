"""The rule for a parameter value typed as text (JSON, or the flow style of `service call`)
and for the JSON a block reads; ParamError, the one-line failure of every parameter tool.
The configuration checks a process's `parameters` values with it when it is loaded."""

from __future__ import annotations

import json
import math
from typing import Any

from ..commands import ControlError


class ParamError(ControlError):
    """A parameter command that failed: one line.  `kind` is the block's word for a refused
    value (not_found, type, size, range, read_only, refused, bad_request) or "" for other
    failures (no such block, the call failed)."""

    def __init__(self, text: str, kind: str = "") -> None:
        super().__init__(text)
        self.kind = kind


def parse_value(text: str) -> Any:
    """A value typed on a command line: JSON, or the flow style of `service call`
    ([1, 2.5, 3], "text", nan, inf); a bare word is a string."""
    try:
        return json.loads(text)
    except ValueError:
        pass
    from ..introspection.request import RequestTextError, _Parser

    parser = _Parser(text)
    try:
        parser.blank()
        value = parser.value()
        parser.blank()
        if parser.pos < len(text):
            raise parser.fail("expected the end of the value")
    except RequestTextError as exc:
        raise ParamError(str(exc).replace("bad request text", "bad value")) from None
    return value


def to_json(value: Any) -> str:
    """A value as the block reads it: JSON, with NaN and the infinities as the strings
    "NaN", "Infinity", "-Infinity"."""
    def fix(v: Any) -> Any:
        if isinstance(v, float) and not math.isfinite(v):
            return "NaN" if math.isnan(v) else "Infinity" if v > 0 else "-Infinity"
        if isinstance(v, list | tuple):
            return [fix(x) for x in v]
        if isinstance(v, dict):
            return {k: fix(x) for k, x in v.items()}
        if not isinstance(v, str | bytes | dict) and hasattr(v, "tolist"):
            return fix(v.tolist())
        return v
    return json.dumps(fix(value), ensure_ascii=False, allow_nan=False)
