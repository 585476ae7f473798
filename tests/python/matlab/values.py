"""The lnmatlab/all_types sample of the round-trip tests, as Python values: the same as
octave/expected_all_types.m."""

from __future__ import annotations

from typing import Any

ALL_TYPES: dict[str, Any] = {
    "c": "A", "name": "hello octave",
    "i8": -128, "u8": 255, "i16": -32768, "u16": 65535,
    "i32": -(2**31), "u32": 2**32 - 1, "i64": -(2**63), "u64": 2**64 - 1,
    "f32": 1.5, "f64": -2.25e100,
    "ai8": [-1, 127], "au8": [0, 1, 255], "ai16": [-2, 300], "au16": [1, 60000],
    "ai32": [-70000, 70000], "au32": [0, 4000000000],
    "ai64": [-(2**63), 2**63 - 1], "au64": [0, 2**64 - 1],
    "af32": [0.25, -3.5], "af64": [1 / 3, -1e-300, float("inf"), 42.0],
    "inner": {"xyz": [1.0, 2.0, 3.0], "flags": 7},
    "points": [{"xyz": [4.0, 5.0, 6.0], "flags": 8}, {"xyz": [7.0, 8.0, 9.0], "flags": 9}],
}


def plain(value: Any) -> Any:
    """A decoded sample as plain lists, dicts and numbers (numpy arrays as lists)."""
    if isinstance(value, dict):
        return {k: plain(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [plain(v) for v in value]
    if hasattr(value, "tolist"):
        return plain(value.tolist())
    return value
