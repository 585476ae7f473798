"""ros2 recordings as Foxglove's viewers decode them: @mcap/core reads the file,
@foxglove/rosmsg parses the ros2msg schema and @foxglove/rosmsg2-serialization decodes the CDR
(mcap_js/decode_ros2.mjs under Node.js).  For every md of test_record_encodings (the topic mds
of message_definitions/, the test mds, a sample of real-world mds) random samples and samples
at the ends of every integer range give back the written values (floats bit for bit as far
as JSON carries them: -0.0, ±inf, NaN), and so does a recording of a real ln_record."""

from __future__ import annotations

import random
import struct
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest

from links_and_nodes.ros2.types import load_md
from ln_generate.model import Struct

from .conftest import Lab
from .mcap_js import js_decode_ros2
from .md_samples import CODES, check, random_sample
from .test_record_encodings import SAMPLES, _cases, _write
from .test_record_encodings_live import N, _packed, _record

CASES = _cases()
FLOAT_ENDS = (-0.0, float("inf"), float("-inf"), float("nan"), 5e-324, 1.7976931348623157e308)


def _ends(layout: Struct, buf: bytearray, base: int, high: bool) -> None:
    """Every integer field at the top (`high`) or bottom of its range, the floats special."""
    for f in layout.fields:
        at = base + f.offset
        if isinstance(f.type, Struct):
            for i in range(f.count):
                _ends(f.type, buf, at + i * f.type.size, high)
        elif f.type.kind == "char":
            continue  # NUL: an empty string, a zero char
        elif f.type.kind == "float":
            code = CODES[f.type.name]
            limit = 3.4028234663852886e38 if code == "f" else FLOAT_ENDS[-1]
            values = [(*FLOAT_ENDS[:-1], limit)[(i + high) % len(FLOAT_ENDS)]
                      for i in range(f.count)]
            if code == "f":  # the smallest float32 subnormal instead of float64's
                values = [1.401298464324817e-45 if v == 5e-324 else v for v in values]
            struct.pack_into(f"<{f.count}{code}", buf, at, *values)
        else:
            code = CODES[f.type.name]
            bits = 8 * f.type.size
            lo, hi = (-(1 << (bits - 1)), (1 << (bits - 1)) - 1) if code.islower() \
                else (0, (1 << bits) - 1)
            struct.pack_into(f"<{f.count}{code}", buf, at, *([hi if high else lo] * f.count))


def _samples(layout: Struct, seed: str) -> list[bytes]:
    rng = random.Random(seed)
    ends = [bytearray(layout.size), bytearray(layout.size)]
    for high, buf in enumerate(ends):
        _ends(layout, buf, 0, bool(high))
    return [bytes(layout.size), *map(bytes, ends),
            *(random_sample(layout, rng) for _ in range(SAMPLES))]


def _attributes(value: Any) -> Any:
    """A decoded message with its fields as attributes, as md_samples.check reads them."""
    if isinstance(value, dict):
        return SimpleNamespace(**{k: _attributes(v) for k, v in value.items()})
    if isinstance(value, list):
        return [_attributes(v) for v in value]
    return value


@pytest.fixture(scope="module")
def decoded(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """Every md's samples written in ros2, one file each, decoded in one Node.js run:
    {case id: (md, samples, what Node decoded of the file)}."""
    top = tmp_path_factory.mktemp("node")
    files: dict[str, tuple[Path, Any, list[bytes]]] = {}
    for i, case in enumerate(CASES):
        name, dirs = case.values
        md = load_md(name, dirs)
        samples = _samples(md.struct, f"node:{case.id}")
        path = top / f"{i}.mcap"
        _write(path, "ros2", name, dirs, samples)
        files[case.id] = (path, md, samples)
    got = js_decode_ros2(*(path for path, _, _ in files.values()))
    return {cid: (md, samples, got[str(path)]) for cid, (path, md, samples) in files.items()}


@pytest.mark.parametrize(("name", "dirs"), CASES)
def test_foxglove_decodes_the_written_values(request: pytest.FixtureRequest,
                                             decoded: dict[str, Any], name: str,
                                             dirs: list[str]) -> None:
    md, samples, topics = decoded[request.node.callspec.id]
    assert "error" not in topics, f"Foxglove's readers cannot decode {name}: {topics['error']}"
    topic = topics["enc.topic"]
    assert (topic["schema_encoding"], topic["message_encoding"]) == ("ros2msg", "cdr")
    messages = topic["messages"]
    assert [m[0] for m in messages] == list(range(1, len(samples) + 1))
    assert [m[3] for m in messages] == [0] * len(samples)  # every byte of the CDR read
    for raw, (_, _, value, _) in zip(samples, messages, strict=True):
        check(md.struct, raw, _attributes(value), "ros2")


def test_foxglove_decodes_a_recording_of_ln_record(lab: Lab) -> None:
    path = _record(lab)  # the default encoding, ros2
    got = js_decode_ros2(path)[str(path)]
    assert "error" not in got, f"Foxglove's readers cannot decode {path}: {got['error']}"
    for topic, md_name in (("enc.a", "rectest/sample"), ("enc.b", "rectest/tool")):
        assert (got[topic]["schema_encoding"], got[topic]["message_encoding"]) == \
            ("ros2msg", "cdr")
        messages = got[topic]["messages"]
        raw = _packed(md_name, range(N))
        assert len(messages) == N and all(m[3] == 0 for m in messages)
        layout = load_md(md_name).struct
        for data, (_, _, value, _) in zip(raw, messages, strict=True):
            check(layout, data, _attributes(value), "ros2")
