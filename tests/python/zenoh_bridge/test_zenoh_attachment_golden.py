"""ln_zenoh's attachment against its schema (wire/zenoh.schema) and the golden vectors of
tests/golden/zenoh_attachment.txt, which the native core's cargo test reads too: wire.py's
codec and the schema-driven wire.codec encode each vector to exactly its bytes and decode the
bytes to its values; every refusal vector is refused with its reason.  No zenoh needed."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from links_and_nodes.wire import codec, schema
from links_and_nodes.wire.gen_cpp_golden import read_golden
from links_and_nodes.zenoh_bridge import wire

GOLDEN = Path(__file__).resolve().parents[2] / "golden" / "zenoh_attachment.txt"
SCHEMA = schema.load(wire.SCHEMA)
CODEC = codec.Codec(SCHEMA)
VECTORS = read_golden(GOLDEN)


def _refusals() -> list[tuple[int, bytes | None, str]]:
    """(line, bytes or None, start of the reason) of each `refuse` line."""
    out = []
    for number, line in enumerate(GOLDEN.read_text(encoding="utf-8").splitlines(), 1):
        word, _, rest = line.partition(" ")
        if word == "refuse":
            data, _, text = rest.partition(" ")
            out.append((number, None if data == "none" else bytes.fromhex(data.strip("-")),
                        text))
    return out


REFUSALS = _refusals()


@pytest.mark.parametrize(("line", "name", "values", "data"), VECTORS,
                         ids=[f"line{v[0]}" for v in VECTORS])
def test_vector(line: int, name: str, values: dict[str, Any], data: bytes) -> None:
    assert name == "ATTACHMENT"
    att = wire.Attachment(values["seq"], values["publish_time_ns"], values["layout_hash"],
                          values["md_name"])
    assert att.encode() == data, f"line {line}"
    assert wire.AttachmentEncoder(att.md_name, att.layout_hash).encode(
        att.seq, att.publish_time_ns) == data, f"line {line}"
    assert wire.decode_attachment(data) == att, f"line {line}"
    fields = {**values, "magic": bytes.fromhex(values["magic"])}
    assert CODEC.encode(name, fields) == data, f"line {line}"
    assert CODEC.decode(name, data) == fields, f"line {line}"


@pytest.mark.parametrize(("line", "data", "why"), REFUSALS, ids=[f"line{r[0]}" for r in REFUSALS])
def test_refusal(line: int, data: bytes | None, why: str) -> None:
    with pytest.raises(wire.AttachmentError) as caught:
        wire.decode_attachment(data)
    assert str(caught.value).startswith(why), f"line {line}"


def test_every_field_is_given_and_the_file_is_complete() -> None:
    names = [f.name for f in SCHEMA.messages["ATTACHMENT"].fields]
    for line, _, values, _ in VECTORS:
        assert list(values) == names, line
    assert len(VECTORS) >= 3 and len(REFUSALS) >= 5


def test_wire_py_follows_the_schema() -> None:
    assert (wire.MAGIC, wire.VERSION) == (SCHEMA.consts["MAGIC"].value.encode(),
                                          SCHEMA.consts["VERSION"].value)
    assert wire.HEAD_SIZE == SCHEMA.consts["HEAD_BYTES"].value == 29
    assert wire.MAX_MD_NAME == SCHEMA.consts["MAX_MD_NAME"].value
    with pytest.raises(ValueError, match="1..255 bytes"):
        wire.Attachment(0, 0, 0, "n" * 256).encode()
