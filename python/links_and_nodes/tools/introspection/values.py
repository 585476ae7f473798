"""Live introspection, the pure part (docs/introspection.md): a topic sample decoded by its
message definition (ln_generate's model) into plain values with the md's field names, a
field picked out of it by a path such as `target.position[2]`, and values formatted for
`topic echo` and `service call`: YAML-like lines with long arrays shortened, or JSON; and
what `topic info` prints of the manager's answer.
Needs neither libln nor a manager."""

from __future__ import annotations

import json
import math
import re
import struct
from typing import Any

from ln_generate.model import Field, Primitive, Struct

# struct module codes of the md primitives (little-endian, packed: "<" in front)
_CODES = {"int8_t": "b", "uint8_t": "B", "int16_t": "h", "uint16_t": "H", "int32_t": "i",
          "uint32_t": "I", "int64_t": "q", "uint64_t": "Q", "float": "f", "double": "d"}
SHOWN = 16  # arrays up to this long are printed whole
HEAD = 8  # of longer ones, this many values, then "... (N values)"

Path = list[str | int]


class IntrospectError(Exception):
    """A request introspection cannot serve (unknown field, bad path, short sample): one line."""


# ---- decoding ----------------------------------------------------------------------------
def float32(value: float) -> float:
    """The shortest decimal that reads back as the same float32 (0.1f is 0.1, not
    0.10000000149011612)."""
    if not math.isfinite(value):
        return value
    for digits in range(6, 10):
        short = float(f"{value:.{digits}g}")
        if struct.unpack("<f", struct.pack("<f", short))[0] == value:
            return short
    return value


def decode(layout: Struct, data: bytes | bytearray | memoryview) -> dict[str, Any]:
    """A packed sample of `layout` as {field: value}: numbers, str for char fields, lists for
    arrays, dicts for nested messages.  A dynamic field is not part of a topic sample (only
    its length is): it shows as a text saying so."""
    if len(data) < layout.size:
        raise IntrospectError(f"sample of {len(data)} bytes, md {layout.md_name!r} needs "
                              f"{layout.size}")
    return _struct(layout, memoryview(data), 0)


def _struct(layout: Struct, buf: memoryview, base: int) -> dict[str, Any]:
    return {f.name: _field(f, buf, base + f.offset) for f in layout.fields}


def _field(f: Field, buf: memoryview, offset: int) -> Any:
    if f.kind == "dynamic":
        count = struct.unpack_from("<I", buf, offset)[0]
        return f"<dynamic field of {count} elements, not carried by topics>"
    if isinstance(f.type, Struct):
        if f.kind == "scalar":
            return _struct(f.type, buf, offset)
        return [_struct(f.type, buf, offset + i * f.type.size) for i in range(f.count)]
    if f.type.kind == "char":
        raw = bytes(buf[offset:offset + f.count])
        return raw.split(b"\0", 1)[0].decode("utf-8", "replace")
    values = list(struct.unpack_from(f"<{f.count}{_CODES[f.type.name]}", buf, offset))
    if f.type.name == "float":
        values = [float32(v) for v in values]
    return values[0] if f.kind == "scalar" else values


def tidy(layout: Struct, values: dict[str, Any]) -> dict[str, Any]:
    """`values` of `layout` (e.g. LnStruct.to_dict() of a service response) with float32
    numbers shown as the float32 they are (see float32)."""
    out = dict(values)
    for f in layout.fields:
        if f.name not in out:
            continue
        value = out[f.name]
        if isinstance(f.type, Struct):
            if isinstance(value, dict):
                out[f.name] = tidy(f.type, value)
            elif isinstance(value, list):
                out[f.name] = [tidy(f.type, v) if isinstance(v, dict) else v for v in value]
        elif f.type.name == "float":
            if isinstance(value, list):
                out[f.name] = [float32(v) for v in value]
            elif isinstance(value, float):
                out[f.name] = float32(value)
    return out


# ---- field paths -------------------------------------------------------------------------
_STEP = re.compile(r"\.?([A-Za-z_][A-Za-z0-9_]*)|\[(\d+)\]")


def parse_path(text: str) -> Path:
    """`target.position[2]` -> ["target", "position", 2]."""
    path: Path = []
    pos = 0
    while pos < len(text):
        match = _STEP.match(text, pos)
        if match is None or (pos == 0 and text.startswith(".")) \
                or (pos > 0 and match.group(1) and not text.startswith(".", pos)):
            raise IntrospectError(f"bad field path {text!r} at column {pos + 1}: expected "
                                  "NAME, .NAME or [INDEX]")
        path.append(match.group(1) if match.group(1) else int(match.group(2)))
        pos = match.end()
    if not path or not isinstance(path[0], str):
        raise IntrospectError(f"bad field path {text!r}: it must start with a field name")
    return path


def check_path(layout: Struct, path: Path) -> None:
    """IntrospectError unless `path` names a value of a sample of `layout`."""
    where = ""
    current: Struct | None = layout  # a message whose fields the next name picks from
    field: Field | None = None  # the field just named, while it is not indexed
    for step in path:
        if isinstance(step, str):
            if current is None and field is not None:
                raise IntrospectError(f"{where!r} is an array: index it first "
                                      f"({where}[0].{step})")
            if current is None:
                raise IntrospectError(f"{where!r} is not a message: it has no field {step!r}")
            names = {f.name: f for f in current.fields}
            if step not in names:
                known = ", ".join(names) or "none"
                raise IntrospectError(f"md {current.md_name!r} has no field {step!r} "
                                      f"{'in ' + repr(where) + ' ' if where else ''}"
                                      f"(its fields: {known})")
            field = names[step]
            where = f"{where}.{step}" if where else step
            if field.kind == "dynamic":
                raise IntrospectError(f"{where!r} is a dynamic field: topics do not carry it")
            current = field.type if field.kind == "scalar" and isinstance(field.type, Struct) \
                else None
            if field.kind == "scalar":
                field = None
        else:
            if field is None or field.kind != "array":
                raise IntrospectError(f"{where!r} is not an array: [{step}] cannot index it")
            if isinstance(field.type, Primitive) and field.type.kind == "char":
                raise IntrospectError(f"{where!r} is a string (char[{field.count}]): it "
                                      "cannot be indexed")
            if step >= field.count:
                raise IntrospectError(f"index {step} out of range: {where!r} has "
                                      f"{field.count} elements")
            where = f"{where}[{step}]"
            current = field.type if isinstance(field.type, Struct) else None
            field = None


def select(values: dict[str, Any], path: Path) -> Any:
    """The value at `path` (checked with check_path) of a decoded sample."""
    value: Any = values
    for step in path:
        value = value[step]
    return value


# ---- formatting --------------------------------------------------------------------------
def _scalar(value: Any) -> str:
    if isinstance(value, str):
        return json.dumps(value, ensure_ascii=False)
    if isinstance(value, float):
        return repr(value) if math.isfinite(value) else str(value)  # nan, inf, -inf
    return str(value)


def format_value(value: Any, full: bool = False) -> str:
    """One line for a scalar or an array of scalars; long arrays shortened to
    `[1.0, 2.0, ... (1000 values)]` unless `full`."""
    if isinstance(value, list):
        if len(value) > SHOWN and not full:
            shown = ", ".join(_scalar(v) for v in value[:HEAD])
            return f"[{shown}, ... ({len(value)} values)]"
        return "[" + ", ".join(_scalar(v) for v in value) + "]"
    return _scalar(value)


def is_block(value: Any) -> bool:
    return isinstance(value, dict) or (isinstance(value, list) and bool(value)
                                       and isinstance(value[0], dict))


def format_block(values: dict[str, Any], full: bool = False, indent: str = "") -> list[str]:
    """YAML-like lines of a decoded message: `name: value`, nested messages indented under
    `name:`, arrays of messages as `- ` items (long ones shortened unless `full`)."""
    lines: list[str] = []
    for name, value in values.items():
        if isinstance(value, dict):
            lines.append(f"{indent}{name}:")
            lines += format_block(value, full, indent + "  ")
        elif is_block(value):
            lines.append(f"{indent}{name}:")
            lines += format_items(value, full, indent + "  ")
        else:
            lines.append(f"{indent}{name}: {format_value(value, full)}")
    return lines


def format_items(items: list[dict[str, Any]], full: bool = False,
                 indent: str = "") -> list[str]:
    """`- ` items of an array of messages (shortened unless `full`)."""
    lines: list[str] = []
    shown = items if full or len(items) <= SHOWN else items[:HEAD]
    for item in shown:
        block = format_block(item, full, indent + "  ") or [indent + "  {}"]
        lines.append(f"{indent}- {block[0][len(indent) + 2:]}")
        lines += block[1:]
    if len(shown) < len(items):
        lines.append(f"{indent}- ... ({len(items)} items)")
    return lines


def format_any(value: Any, full: bool = False) -> list[str]:
    """What `--field` prints of one sample: one line, or a block for messages."""
    if isinstance(value, dict):
        return format_block(value, full)
    if is_block(value):
        return format_items(value, full)
    return [format_value(value, full)]


def publish_time(timestamp_ns: int) -> str:
    """A publish time (CLOCK_REALTIME ns) as seconds with all nine decimals."""
    return f"{timestamp_ns // 1_000_000_000}.{timestamp_ns % 1_000_000_000:09d}"


def header(seq: int, timestamp_ns: int) -> str:
    """The line before each sample `topic echo` prints."""
    return f"--- seq {seq}, published {publish_time(timestamp_ns)}"


def jsonable(value: Any) -> Any:
    """`value` for strict JSON: NaN and infinities become the strings "NaN", "Infinity",
    "-Infinity" (JSON has no numbers for them)."""
    if isinstance(value, float) and not math.isfinite(value):
        return "NaN" if math.isnan(value) else ("Infinity" if value > 0 else "-Infinity")
    if isinstance(value, dict):
        return {k: jsonable(v) for k, v in value.items()}
    if isinstance(value, list):
        return [jsonable(v) for v in value]
    return value


def sample_record(seq: int, timestamp_ns: int, data: Any,
                  field: str | None = None) -> dict[str, Any]:
    """One sample as `topic echo --json` prints it and `topic_echo()` returns it."""
    record: dict[str, Any] = {"seq": seq, "publish_time": timestamp_ns / 1e9,
                              "publish_time_ns": timestamp_ns}
    if field is not None:
        record["field"] = field
    record["data"] = data
    return record


def json_line(value: Any) -> str:
    return json.dumps(jsonable(value), ensure_ascii=False, allow_nan=False)


def info_lines(info: dict[str, Any]) -> list[str]:
    """What `topic info` prints."""
    lines = [f"topic: {info['name']} (id {info['id']})",
             f"md: {info['md_name']} (layout hash {info['layout_hash']}, "
             f"{info['message_size']} bytes)",
             f"ring: {info['slots']} slots, {info['ring_bytes']} bytes"
             + ("; adopted after a manager restart" if info["adopted"] else "")]
    for ring in info["rings"]:
        lines.append(f"  on {ring['host']}: {ring['segment']}"
                     + (f" (generations: {', '.join(ring['generations'])})"
                        if len(ring["generations"]) > 1 else ""))
    lines.append(f"published: {info['published']} samples")
    lines.append(f"publishers: {len(info['publishers'])}")
    for pub in info["publishers"]:
        waits = ", waits for subscribers" if pub["wait_for_subscribers"] else ""
        lines.append(f"  {pub['client']} (pid {pub['pid']}, host {pub['host']}): port "
                     f"{pub['port']}, {pub['buffers']} buffer{'s' * (pub['buffers'] > 1)}"
                     f"{waits}{_other_md(pub, info)}")
    lines.append(f"subscribers: {len(info['subscribers'])}")
    for sub in info["subscribers"]:
        mode = "latest" if sub["mode"] == "latest" else f"queued, {sub['buffers']} buffers"
        lines.append(f"  {sub['client']} (pid {sub['pid']}, host {sub['host']}): port "
                     f"{sub['port']}, {mode}, reader {sub['reader']}, {sub['transport']}"
                     f"{_other_md(sub, info)}")
    if info["streams"]:
        lines.append("forwarded:")
        for s in info["streams"]:
            lines.append(f"  {s['src']} -> {s['dst']} over {s['transport']}: "
                         f"{s['msgs_per_s']:.1f} samples/s, {s['bytes_per_s']} bytes/s, "
                         f"{s['drops']} drops" + (f", {s['error']}" if s["error"] else ""))
    return lines


def _other_md(port: dict[str, Any], info: dict[str, Any]) -> str:
    return f", md {port['md_name']}" if port["md_name"] != info["md_name"] else ""
