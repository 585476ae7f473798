"""The pure part of live introspection (introspect.py): samples decoded by the md model into
the values the generated Python types hold, field paths and their errors, and the output
formats of `topic echo` (shortened arrays, blocks, JSON lines).  No libln, no manager."""

from __future__ import annotations

import ctypes
import json
import math
import struct

import pytest

import links_and_nodes as ln
from links_and_nodes.tools.introspection import values as fmt
from links_and_nodes.tools.introspection.client import load_md
from links_and_nodes.tools.introspection.values import IntrospectError

from .conftest import MDS, REPO

VALID = str(REPO / "tests" / "fixtures" / "md" / "valid")
ln.add_message_definition_dir(VALID)
ln.add_message_definition_dir(MDS)


def test_float32_shows_the_shortest_decimal_of_the_float32() -> None:
    for text in ("0.1", "0.2", "1e-07", "3.4028235e+38", "16777216.0", "-2.5"):
        stored = struct.unpack("<f", struct.pack("<f", float(text)))[0]
        assert fmt.float32(stored) == float(text)
    assert math.isnan(fmt.float32(math.nan)) and fmt.float32(-math.inf) == -math.inf


def test_decode_gives_what_the_generated_type_holds_for_every_primitive() -> None:
    md = load_md("lntest/all_types", [VALID])
    cls = ln.message_class("lntest/all_types")
    values = {"c": "x", "i8": -128, "u8": 255, "i16": -32768, "u16": 65535,
              "i32": -(2 ** 31), "u32": 2 ** 32 - 1, "i64": -(2 ** 63), "u64": 2 ** 64 - 1,
              "f32": 0.1, "f64": 0.1, "f32_alias": -1.5, "f64_alias": 1e300, "int_alias": 7,
              "short_alias": -7, "name": "arm ä", "one_char": "z", "i8s": [-1, 0, 1],
              "u8s": [1, 2, 3, 4, 5], "i16s": [-2, 2], "u16s": [3, 4], "i32s": [-5, 6, 7],
              "u32s": [8, 9, 10], "i64s": [-(2 ** 40), 2 ** 40], "u64s": [0, 2 ** 64 - 1],
              "f32s": [0.25, 0.3, -0.7], "f64s": [1.5, -2.5, math.pi],
              "f32_aliases": [1.0, 0.1], "f64_aliases": [2.0, 0.2], "int_aliases": [-1, 1],
              "short_aliases": [1, 2, 3]}
    sample = cls.from_dict(values)
    decoded = fmt.decode(md.struct, bytes(sample))
    assert decoded == values
    assert list(decoded) == [f.name for f in md.struct.fields]  # md order


def test_decode_nested_arrays_of_messages_and_dynamic_fields() -> None:
    md = load_md("lntest/outer", [VALID])
    cls = ln.message_class("lntest/outer")
    sample = cls()
    sample.t.sec, sample.t.nsec = 1700000000, 5
    sample.m.flag = 1
    sample.m.one.a = -3
    sample.m.one.tag = "ab"
    sample.m.many[2].b = [0.5, 0.1]
    sample.ms[1].one.a = 9
    sample.p.position = [1, 2, 3]
    sample.ds = [{"flag": 2}]
    sample.note = "hello"
    sample.tail = 2.5
    decoded = fmt.decode(md.struct, bytes(sample))
    assert decoded["t"] == {"sec": 1700000000, "nsec": 5}
    assert decoded["m"]["one"] == {"a": -3, "b": [0.0, 0.0], "tag": "ab"}
    assert decoded["m"]["many"][2]["b"] == [0.5, 0.1]
    assert decoded["ms"][1]["one"]["a"] == 9 and len(decoded["ms"]) == 2
    assert decoded["p"]["position"] == [1.0, 2.0, 3.0]
    # a topic carries no dynamic data, only the lengths: said as text
    assert decoded["ds"] == "<dynamic field of 1 elements, not carried by topics>"
    assert decoded["note"] == "<dynamic field of 5 elements, not carried by topics>"
    assert decoded["m"]["dyn"] == "<dynamic field of 0 elements, not carried by topics>"
    assert decoded["tail"] == 2.5


def test_decode_refuses_a_short_sample() -> None:
    md = load_md("lntest/probe", [str(MDS)])
    with pytest.raises(IntrospectError, match="sample of 10 bytes, md 'lntest/probe' needs 940"):
        fmt.decode(md.struct, b"\0" * 10)


def test_tidy_shows_float32_fields_of_plain_values() -> None:
    md = load_md("lntest/probe", [str(MDS)])
    raw = ln.message_class("lntest/probe").from_dict({"gains": [0.1, 0.2, 0.3]}).to_dict()
    assert raw["gains"] != [0.1, 0.2, 0.3]  # doubles of the float32 values
    assert fmt.tidy(md.struct, raw)["gains"] == [0.1, 0.2, 0.3]


# ---- field paths -------------------------------------------------------------------------
def test_paths_parse_select_and_check() -> None:
    md = load_md("lntest/outer", [VALID])
    assert fmt.parse_path("ms[1].many[2].b[0]") == ["ms", 1, "many", 2, "b", 0]
    for good in ("tail", "ms[1].one.tag", "m.many", "p.orientation[3]", "ms"):
        fmt.check_path(md.struct, fmt.parse_path(good))
    values = {"ms": [{"one": {"a": 1}}, {"one": {"a": 2}}]}
    assert fmt.select(values, fmt.parse_path("ms[1].one.a")) == 2


@pytest.mark.parametrize(("path", "error"), [
    ("", "bad field path '': it must start with a field name"),
    ("[1]", "bad field path '[1]': it must start with a field name"),
    (".tail", "bad field path '.tail' at column 1: expected NAME, .NAME or [INDEX]"),
    ("tail.", "bad field path 'tail.' at column 5: expected NAME, .NAME or [INDEX]"),
    ("ms[1]one", "bad field path 'ms[1]one' at column 6: expected NAME, .NAME or [INDEX]"),
    ("ms[-1]", "bad field path 'ms[-1]' at column 3: expected NAME, .NAME or [INDEX]"),
])
def test_bad_path_syntax(path: str, error: str) -> None:
    with pytest.raises(IntrospectError) as info:
        fmt.parse_path(path)
    assert str(info.value) == error


@pytest.mark.parametrize(("path", "error"), [
    ("nope", "md 'lntest/outer' has no field 'nope' (its fields: t, m, ms, p, ds, note, "
             "tail)"),
    ("m.one.zz", "md 'lntest/inner' has no field 'zz' in 'm.one' (its fields: a, b, tag)"),
    ("ms.one", "'ms' is an array: index it first (ms[0].one)"),
    ("ms[2]", "index 2 out of range: 'ms' has 2 elements"),
    ("tail[0]", "'tail' is not an array: [0] cannot index it"),
    ("tail.x", "'tail' is not a message: it has no field 'x'"),
    ("m.one.tag[1]", "'m.one.tag' is a string (char[4]): it cannot be indexed"),
    ("ds", "'ds' is a dynamic field: topics do not carry it"),
    ("p.position[0][1]", "'p.position[0]' is not an array: [1] cannot index it"),
])
def test_paths_the_md_does_not_have(path: str, error: str) -> None:
    md = load_md("lntest/outer", [VALID])
    with pytest.raises(IntrospectError) as info:
        fmt.check_path(md.struct, fmt.parse_path(path))
    assert str(info.value) == error


# ---- formats -----------------------------------------------------------------------------
def test_long_arrays_are_shortened_unless_full() -> None:
    values = [float(i) for i in range(1000)]
    assert fmt.format_value(values) == \
        "[0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, ... (1000 values)]"
    assert fmt.format_value(values, full=True) == "[" + ", ".join(map(str, values)) + "]"
    assert fmt.format_value(list(range(16))) == "[" + ", ".join(map(str, range(16))) + "]"
    assert fmt.format_value([math.nan, math.inf, -math.inf, "a\"b"]) == \
        '[nan, inf, -inf, "a\\"b"]'


def test_blocks_nest_messages_and_list_arrays_of_them_as_items() -> None:
    value = {"a": 1, "p": {"x": [1.5, 2.5], "name": "arm"},
             "items": [{"k": 1, "sub": {"z": 0}}, {"k": 2, "sub": {"z": 1}}], "empty": []}
    assert fmt.format_block(value) == [
        "a: 1", "p:", "  x: [1.5, 2.5]", '  name: "arm"', "items:", "  - k: 1", "    sub:",
        "      z: 0", "  - k: 2", "    sub:", "      z: 1", "empty: []"]
    many = [{"k": i} for i in range(20)]
    lines = fmt.format_items(many)
    assert lines[:2] == ["- k: 0", "- k: 1"] and lines[-1] == "- ... (20 items)"
    assert len(lines) == fmt.HEAD + 1
    assert len(fmt.format_items(many, full=True)) == 20


def test_header_json_and_records() -> None:
    assert fmt.header(42, 1_700_000_000_000_000_005) == \
        "--- seq 42, published 1700000000.000000005"
    record = fmt.sample_record(42, 1_700_000_000_500_000_000, {"v": math.nan}, "v")
    assert json.loads(fmt.json_line(record)) == {
        "seq": 42, "publish_time": 1700000000.5, "publish_time_ns": 1_700_000_000_500_000_000,
        "field": "v", "data": {"v": "NaN"}}
    assert fmt.jsonable([math.inf, -math.inf, 1.0]) == ["Infinity", "-Infinity", 1.0]


def test_decoded_probe_sample_formats_like_topic_echo() -> None:
    md = load_md("lntest/probe", [str(MDS)])
    sample = ln.message_class("lntest/probe").from_dict({
        "count": 3, "q": [3 + j / 8 for j in range(7)], "label": "probe",
        "trace": [3000 + i for i in range(100)]})
    lines = fmt.format_block(fmt.decode(md.struct, bytes(sample)))
    assert lines[0] == "count: 3"
    assert lines[-1] == ("trace: [3000.0, 3001.0, 3002.0, 3003.0, 3004.0, 3005.0, 3006.0, "
                         "3007.0, ... (100 values)]")
    assert ctypes.sizeof(sample) == md.struct.size == 940
