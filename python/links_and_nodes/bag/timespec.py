"""The time syntax of `ln_bag cut --start/--end` and `split --duration`.

    1733560000123456789          absolute: ns since the Unix epoch (digits only)
    2026-12-07T06:40:54.5Z       absolute: ISO 8601 with a zone (Z or +01:00), up to ns
    +12.5  or  12.5s  or  +12.5s relative: seconds after the first sample of the input(s)

Decimal seconds are exact to the ns (more than 9 decimals is refused)."""

from __future__ import annotations

import argparse
import re
from dataclasses import dataclass
from datetime import datetime
from decimal import Decimal, InvalidOperation

_RELATIVE = re.compile(r"\+(\d+(?:\.\d*)?|\.\d+)s?|(\d+(?:\.\d*)?|\.\d+)s")
_ISO = re.compile(r"(\d{4}-\d{2}-\d{2}[T ]\d{2}:\d{2}(?::\d{2})?)(?:\.(\d{1,9}))?"
                  r"(Z|[+-]\d{2}:?\d{2})")


@dataclass(frozen=True)
class TimeSpec:
    """A point in time: `ns` since the epoch, or `ns` after the first sample (relative)."""

    ns: int
    relative: bool
    text: str

    def resolve(self, first_ns: int | None) -> int:
        """Absolute ns; a relative time needs the input's first sample time."""
        if not self.relative:
            return self.ns
        return (first_ns or 0) + self.ns


def seconds_ns(text: str) -> int:
    """ns of a decimal number of seconds, exactly; ValueError if not one."""
    try:
        value = Decimal(text)
    except InvalidOperation:
        raise ValueError(f"not a number of seconds: {text!r}") from None
    ns = value * 1_000_000_000
    if not value.is_finite() or ns != ns.to_integral_value():
        raise ValueError(f"not a number of seconds with at most 9 decimals: {text!r}")
    return int(ns)


def parse_time(text: str) -> TimeSpec:
    """The TimeSpec of `text` (syntax above); argparse.ArgumentTypeError otherwise."""
    s = text.strip()
    if s.isdigit():
        return TimeSpec(int(s), False, text)
    m = _RELATIVE.fullmatch(s)
    if m:
        return TimeSpec(seconds_ns(m.group(1) or m.group(2)), True, text)
    m = _ISO.fullmatch(s)
    if m:
        zone = "+00:00" if m.group(3) == "Z" else m.group(3)
        try:
            base = datetime.fromisoformat(m.group(1).replace(" ", "T") + zone)
        except ValueError as exc:
            raise argparse.ArgumentTypeError(f"not a time: {text!r}: {exc}") from None
        frac = int((m.group(2) or "").ljust(9, "0"))
        return TimeSpec(int(base.timestamp()) * 1_000_000_000 + frac, False, text)
    raise argparse.ArgumentTypeError(
        f"not a time: {text!r} (ns since the epoch like 1733560000123456789, ISO 8601 "
        "with a zone like 2026-12-07T06:40:54.5Z, or seconds after the first sample like "
        "+12.5 or 12.5s)")


def parse_duration(text: str) -> int:
    """ns of a positive duration in seconds (`10`, `2.5`, `10s`)."""
    try:
        ns = seconds_ns(text[:-1] if text.endswith("s") else text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    if ns <= 0:
        raise argparse.ArgumentTypeError(f"not a positive number of seconds: {text!r}")
    return ns
