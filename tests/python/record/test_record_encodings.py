"""The `ros2` and `json` encodings of recordings (record/encodings.py), without a manager: for
every topic md of message_definitions/, the test mds and a sample of real-world mds, random
samples written as channels, read back with the PyPI readers (mcap with mcap-ros2-support's
decoder; json.loads against the channel's JSON Schema), their values equal to the packed
ones (floats bit for bit), and ln_decoder giving back every byte; mds the mapping refuses."""

from __future__ import annotations

import json
import random
from pathlib import Path
from typing import Any

import pytest

from links_and_nodes.mcap_format import McapReader, McapWriter, md_schema_text
from links_and_nodes.record.encodings import EncodingError, channel_encoder, ln_decoder
from links_and_nodes.ros2.types import load_md

from .conftest import MD_DIR, pypi_mcap
from .md_samples import check, random_sample

ROOT = Path(__file__).resolve().parents[3]
REAL_MD = ROOT.parent / "shared" / "real_ln" / "md"  # beside the checkout, as CI has it
REAL_SAMPLE = 12  # real-world topic mds taken (every n-th of those that fit, sorted)
SAMPLES = 6


def _md_names(top: Path) -> list[str]:
    return sorted(str(p.relative_to(top)) for p in top.rglob("*")
                  if p.is_file() and "." not in p.name and p.name != "SConscript")


def _fits(name: str, dirs: list[str]) -> bool:
    try:
        md = load_md(name, dirs)
    except Exception:  # noqa: BLE001 - a file that is not an md here
        return False
    return md.kind == "message" and not md.struct.has_dynamic


def _cases() -> list[Any]:
    cases = [(name, [str(ROOT / "message_definitions")])
             for name in _md_names(ROOT / "message_definitions")]
    cases += [(name, [str(MD_DIR)]) for name in _md_names(MD_DIR)]
    cases = [c for c in cases if _fits(*c)]
    if REAL_MD.is_dir():
        real = [(name, [str(top)]) for top in sorted(REAL_MD.iterdir()) if top.is_dir()
                for name in _md_names(top)]
        real = [c for c in real if _fits(*c)]
        cases += real[::max(1, len(real) // REAL_SAMPLE)][:REAL_SAMPLE]
    return [pytest.param(name, dirs, id=f"{Path(dirs[0]).name}:{name}") for name, dirs in cases]


def _schema_keys(value: Any, schema: dict[str, Any], where: str = "$") -> None:
    """The object keys of a JSON sample are those of its schema, at every level."""
    if schema.get("type") == "object":
        assert list(value) == list(schema["properties"]) == schema["required"], where
        for k, v in value.items():
            _schema_keys(v, schema["properties"][k], f"{where}.{k}")
    elif schema.get("type") == "array" and isinstance(schema["items"], dict):
        for i, v in enumerate(value):
            _schema_keys(v, schema["items"], f"{where}[{i}]")


def _write(path: Path, encoding: str, name: str, dirs: list[str], samples: list[bytes]) -> Any:
    md = load_md(name, dirs)
    enc = channel_encoder(encoding, name, md_schema_text(name, dirs), md.layout_hash,
                          md.struct.size)
    with McapWriter(path, "zstd", chunk_size=1 << 12) as out:
        ch = enc.add_to(out, "enc.topic")
        for i, raw in enumerate(samples):
            out.write(ch, i + 1, 1000 + i, enc.encode(raw))
    return md


@pytest.mark.parametrize(("name", "dirs"), _cases())
@pytest.mark.parametrize("encoding", ["ros2", "json"])
def test_encoding_decodes_to_the_values_and_back_to_the_bytes(
        tmp_path: Path, encoding: str, name: str, dirs: list[str]) -> None:
    rng = random.Random(f"{encoding}:{name}")
    path = tmp_path / "enc.mcap"
    md = load_md(name, dirs)
    samples = [bytes(md.struct.size)] + [random_sample(md.struct, rng) for _ in range(SAMPLES)]
    _write(path, encoding, name, dirs, samples)

    pypi_mcap()
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        if encoding == "ros2":
            got = [(sch.encoding, ch.message_encoding, decoded) for sch, ch, _, decoded
                   in reader.iter_decoded_messages()]
            assert {g[:2] for g in got} == {("ros2msg", "cdr")}
            values = [g[2] for g in got]
        else:
            got = [(sch, ch, msg) for sch, ch, msg in reader.iter_messages()]
            assert {(s.encoding, c.message_encoding) for s, c, _ in got} == {
                ("jsonschema", "json")}
            schema = json.loads(got[0][0].data)
            values = [json.loads(m.data) for _, _, m in got]
            for v in values:
                _schema_keys(v, schema)
    assert len(values) == len(samples)
    for raw, value in zip(samples, values, strict=True):
        check(md.struct, raw, value, encoding)

    # back to the ln bytes, from the recorded md text alone (no md directory searched)
    mcap = McapReader(path)
    info = mcap.topics()["enc.topic"]
    assert info.md_name == name and info.layout_hash == md.layout_hash
    to_ln = ln_decoder(info, md_dirs=[])
    assert [to_ln(s.data) for s in mcap] == samples


def test_refusals_name_the_md_and_the_reason() -> None:
    text = md_schema_text("ln/string")
    for encoding in ("ros2", "json"):
        with pytest.raises(EncodingError, match=r"ln/string.*dynamic"):
            channel_encoder(encoding, "ln/string", text, 0, 16)
    with pytest.raises(EncodingError, match="unknown encoding 'cbor'"):
        channel_encoder("cbor", "ln/string", text, 0, 16)
    md = load_md("rectest/sample", [str(MD_DIR)])
    with pytest.raises(EncodingError, match="layout hash"):
        channel_encoder("json", "rectest/sample", md_schema_text("rectest/sample", [str(MD_DIR)]),
                        md.layout_hash ^ 1, md.struct.size)


def test_bad_stored_bytes_raise_with_the_topic(tmp_path: Path) -> None:
    dirs = [str(MD_DIR)]
    for encoding, bad, what in [("json", b'{"counter": 1}', "value: missing"),
                                ("json", b'{"counter": 1', "line 1 column"),
                                ("ros2", b"\x00\x01\x00\x00\x01", "at byte")]:
        path = tmp_path / f"{encoding}.mcap"
        _write(path, encoding, "rectest/sample", dirs, [])
        info = McapReader(path).topics()["enc.topic"]
        with pytest.raises(EncodingError, match=rf"topic 'enc.topic'.*{what}"):
            ln_decoder(info)(bad)


@pytest.mark.parametrize("encoding", ["ros2", "json", "ln"])
def test_logger_save_writes_the_encoding_and_keeps_unknown_mds_raw(
        tmp_path: Path, encoding: str) -> None:
    from links_and_nodes import logger_files as lf

    md = load_md("robot/joint_state", [str(ROOT / "message_definitions")])
    rng = random.Random(encoding)
    samples = [(i, 1000 * i, random_sample(md.struct, rng)) for i in range(1, 6)]
    stats = {"received": 5, "missed": 0, "skipped": 0, "dropped": 0, "start_seq": 0}
    known = lf.new_entry("robot/joint_state", md.layout_hash, md.struct.size, 1)
    lf.add_host(known, "h", samples, stats)
    unknown = lf.new_entry("elsewhere/only", 0x1234, 4, 1)  # an md this host does not have
    lf.add_host(unknown, "h", [(1, 1500, b"abcd")], {**stats, "received": 1})
    path = tmp_path / "saved.mcap"
    result = lf.save({"arm.state": known, "other": unknown}, path, encoding)
    assert result["topics"]["arm.state"]["encoding"] == encoding
    assert result["topics"]["other"]["encoding"] == "ln"
    mcap = McapReader(path)
    topics = mcap.topics()
    assert topics["arm.state"].message_encoding == {"ros2": "cdr", "json": "json",
                                                    "ln": "ln-md"}[encoding]
    decoders = {name: ln_decoder(info) for name, info in topics.items()}
    got = [(s.topic, s.seq, s.publish_time_ns, decoders[s.topic](s.data)) for s in mcap]
    assert sorted(got) == sorted([("arm.state", *s) for s in samples]
                                 + [("other", 1, 1500, b"abcd")])
    with pytest.raises(ValueError, match="for .mcap files"):
        lf.save({"arm.state": known}, tmp_path / "x.npz", encoding="json")
