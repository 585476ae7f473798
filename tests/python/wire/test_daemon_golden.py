"""The schema-driven Python codec of the manager <-> ln_daemon protocol (wire/codec.py,
wire/daemon.schema) against tests/wire/daemon_golden.txt, the vectors the daemon's generated
C++ codec must produce too (tests/ln_daemon/test_daemon_golden.cpp): each vector encodes to
exactly its bytes and decodes back to its values, no shorter payload and no longer one
decodes, and every message of the schema has a vector."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from links_and_nodes.wire import codec, schema
from links_and_nodes.wire.gen_cpp_golden import read_golden

GOLDEN = Path(__file__).resolve().parents[2] / "wire" / "daemon_golden.txt"
D = codec.DAEMON


VECTORS = read_golden(GOLDEN)


def _to_codec(struct_name: str, obj: dict[str, Any]) -> dict[str, Any]:
    """The golden file's JSON as codec values: hex strings of byte fields become bytes."""
    out: dict[str, Any] = {}
    for f in D.schema.struct(struct_name).fields:
        if f.type.kind == "flags":
            out.update({b.name: obj[b.name] for b in D.schema.enums[f.type.ref or ""].entries})
        else:
            out[f.name] = _convert(f.type, obj[f.name])
    return out


def _convert(t: schema.Type, v: Any) -> Any:
    if t.kind in ("bytes", "fixed", "tail"):
        return bytes.fromhex(v)
    if t.kind == "record":
        return _to_codec(t.ref or "", v)
    if t.kind == "list":
        assert t.item is not None
        return [_convert(t.item, x) for x in v]
    if t.kind == "enum":
        return D.enums[t.ref or ""][v]
    return v


@pytest.mark.parametrize(("line", "name", "values", "payload"), VECTORS,
                         ids=[f"{v[1]}@{v[0]}" for v in VECTORS])
def test_vector(line: int, name: str, values: dict[str, Any], payload: bytes) -> None:
    expected = _to_codec(name, values)
    assert D.encode(name, expected) == payload, f"line {line}"
    assert D.decode(name, payload) == expected, f"line {line}"
    tail = next((f.name for f in D.schema.messages[name].fields if f.type.kind == "tail"), None)
    head = len(payload) - (len(expected[tail]) if tail else 0)  # a tail takes any length
    for cut in range(head):
        with pytest.raises(codec.WireError):
            D.decode(name, payload[:cut])
    if tail is None:
        with pytest.raises(codec.WireError, match="left over"):
            D.decode(name, payload + b"\0")


def test_every_message_has_a_vector() -> None:
    assert {v[1] for v in VECTORS} == set(D.schema.messages)


def test_every_field_is_given() -> None:
    # a vector that leaves a field out would test the default, not the value
    for line, name, values, _ in VECTORS:
        assert _to_codec(name, values).keys() >= {
            f.name for f in D.schema.messages[name].fields if f.type.kind != "flags"}, line


def test_refusals() -> None:
    with pytest.raises(codec.WireError, match="unknown bits"):
        D.decode("SPAWN", D.encode("SPAWN", {"name": "x"})[:5] + b"\x04"
                 + D.encode("SPAWN", {"name": "x"})[6:])
    with pytest.raises(codec.WireError, match="no Transport"):
        D.encode("STREAM_RECV", {"transport": 7})
    with pytest.raises(codec.WireError, match="more than 255"):
        D.encode("STOP", {"name": "x" * 256})
    with pytest.raises(codec.WireError, match="does not fit u16"):
        D.encode("NET_DETAILS", {"data_port": 70000})
    bad_bool = D.encode("SIGNAL", {"name": "a", "group": True})[:-1] + b"\x02"
    with pytest.raises(codec.WireError, match="bool"):
        D.decode("SIGNAL", bad_bool)
    huge_count = (1000).to_bytes(4, "little")
    with pytest.raises(codec.WireError, match="short payload for a count of 1000"):
        D.decode("PROCESS_LIST", huge_count + bytes(40))
