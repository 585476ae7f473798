"""The columns of a topic for export: one per scalar field of its md, arrays flattened as
`name[i]` (`name[i][j]` for two dimensions), nested fields as `a.b`, after `seq` and
`publish_time`; as a numpy dtype over the record `seq (u8), publish_time (i8), sample`."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import numpy as np

from ..logger_files import HEAD_FIELDS, SAMPLE_HEAD, message_dtype
from ..mcap_format import TopicInfo, schema_message_class


def md_dtype(info: TopicInfo) -> np.dtype:
    """The numpy dtype of a channel's md: built from the text the recording carries, else
    the md installed here, else one opaque `data` field of the sample's size."""
    if info.md_text:
        try:
            cls = schema_message_class(info.md_name, info.md_text)
            dtype = np.dtype(cls)
            if cls.LAYOUT_HASH == info.layout_hash and dtype.itemsize == info.message_size:
                return dtype
        except Exception:  # noqa: BLE001 - an unusable recorded text: try the installed md
            pass
    return message_dtype(info.md_name, info.message_size)


def _leaves(dtype: np.dtype, name: str, offset: int) -> Iterator[tuple[str, Any, int]]:
    if dtype.names:
        for field in dtype.names:
            sub, off = dtype.fields[field][:2]
            yield from _leaves(sub, f"{name}.{field}" if name else field, offset + off)
    elif dtype.subdtype is not None and dtype.subdtype[0].kind != "S":
        base, shape = dtype.subdtype
        for flat, idx in enumerate(np.ndindex(*shape)):
            yield from _leaves(base, name + "".join(f"[{i}]" for i in idx),
                               offset + flat * base.itemsize)
    elif dtype.subdtype is not None:  # char[N]: one text column
        yield name, f"S{dtype.itemsize}", offset
    else:
        yield name, dtype, offset


def flat_dtype(md: np.dtype) -> np.dtype:
    """The columns over a record of SAMPLE_HEAD + sample (see the module text)."""
    names, formats, offsets = [], [], []
    for name, fmt, off in [(n, f, o) for (n, f), o in zip(HEAD_FIELDS, (0, 8), strict=True)]:
        names.append(name)
        formats.append(fmt)
        offsets.append(off)
    for name, fmt, off in _leaves(md, "", 0):
        names.append(name)
        formats.append(fmt)
        offsets.append(SAMPLE_HEAD.size + off)
    return np.dtype({"names": names, "formats": formats, "offsets": offsets,
                     "itemsize": SAMPLE_HEAD.size + md.itemsize})


def cell(value: Any) -> Any:
    """A CSV cell of one column value: text for char fields, hex for opaque bytes."""
    if isinstance(value, bytes):
        return value.decode("utf-8", errors="backslashreplace")
    if isinstance(value, (memoryview, np.void)):
        return bytes(value).hex()
    return value
