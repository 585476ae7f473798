"""The manager's client <-> manager codec (tools/protocol.py, built from
wire/client.schema) against tests/wire/client_golden.txt, the golden frames libln's generated
C codec must produce too (tests/c/test_client_golden.c): each message encodes to exactly its
frame and decodes back to itself; the schema-driven wire.codec agrees; every type is there."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import pytest

from links_and_nodes.tools import protocol as p
from links_and_nodes.wire import codec, schema

GOLDEN = Path(__file__).resolve().parents[2] / "wire" / "client_golden.txt"
_VALUE = re.compile(r'([\w.]+)=("(?:[^"\\]|\\.)*"|\S+)')


def _unquote(text: str) -> str:
    raw = bytearray()
    i = 1
    while i < len(text) - 1:
        if text[i] == "\\" and text[i + 1] == "x":
            raw.append(int(text[i + 2:i + 4], 16))
            i += 4
        else:
            if text[i] == "\\":
                i += 1
            raw += text[i].encode()
            i += 1
    return raw.decode("utf-8")


def _vectors() -> list[tuple[int, str, list[tuple[str, str]], bytes]]:
    """(line, type name, [(field, value text)], frame) of every vector of the file."""
    vectors: list[tuple[int, str, list[tuple[str, str]], bytes]] = []
    hex_digits: list[str] = []
    for number, line in enumerate(GOLDEN.read_text(encoding="utf-8").splitlines(), 1):
        if not line or line.startswith("#"):
            continue
        if line.startswith(" "):
            hex_digits.append(line)
            continue
        if vectors:
            vectors[-1] = (*vectors[-1][:3], bytes.fromhex("".join(hex_digits)))
        hex_digits = []
        name, _, rest = line.partition(" ")
        vectors.append((number, name, _VALUE.findall(rest), b""))
    if vectors:
        vectors[-1] = (*vectors[-1][:3], bytes.fromhex("".join(hex_digits)))
    return vectors


def _build(cls: type[p.Record], values: list[tuple[str, str]], prefix: str = "") -> Any:
    """An instance of `cls` from the vector's values (consumed from the front)."""
    args = []
    for name, kind in cls.FIELDS:
        key, text = values.pop(0)
        assert key == prefix + name, f"expected field {prefix + name}, got {key}"
        if isinstance(kind, type):
            args.append(tuple(_build(kind, values, f"{prefix}{name}.{index}.")
                              for index in range(int(text, 0))))
        elif kind in ("str", "text"):
            args.append(_unquote(text))
        else:
            args.append(int(text, 0))
    return cls(*args)


def _as_dict(record: p.Record) -> dict[str, Any]:
    return {name: ([_as_dict(item) for item in getattr(record, name)]
                   if isinstance(kind, type) else getattr(record, name))
            for name, kind in record.FIELDS}


VECTORS = _vectors()


@pytest.mark.parametrize("line,name,values,frame", VECTORS, ids=[f"{v[1]}@{v[0]}" for v in VECTORS])
def test_golden_frame(line: int, name: str, values: list[tuple[str, str]], frame: bytes) -> None:
    cls = p.MESSAGES[p.MsgType[name]]
    remaining = list(values)
    msg = _build(cls, remaining)
    assert not remaining, f"line {line}: fields left over: {remaining}"
    assert p.encode(msg) == frame
    assert p.decode_frame(frame) == msg
    # The schema-driven codec of wire/codec.py reads the same schema: the same body.
    client = codec.Codec(schema.load(schema.CLIENT_SCHEMA))
    body = frame[p.HEADER_SIZE + 2:]
    assert client.encode(name, _as_dict(msg)) == body
    assert client.decode(name, body) == _as_dict(msg)


def test_every_message_type_has_a_golden_frame() -> None:
    assert {name for _, name, _, _ in VECTORS} == {t.name for t in p.MsgType}


def test_classes_follow_the_schema() -> None:
    """Each message class has the schema's fields, in order, and its direction."""
    loaded = schema.load(schema.CLIENT_SCHEMA)
    for msg in loaded.messages.values():
        cls = p.MESSAGES[loaded.message_enum.value(msg.name) or 0]
        assert cls.__name__ == msg.type_name
        assert [name for name, _ in cls.FIELDS] == [f.name for f in msg.fields]
        assert cls.FROM_CLIENT == (msg.sender == "client")
