"""CDR (XCDR1, little-endian) encoding of ln topic samples and back, compiled per md.

The md's layout is flattened once into leaves (a primitive or primitive array, or a char[N]
string) and cut at the strings into blocks.  A block is laid out into copy runs for each of
the 8 possible start positions modulo 8 (on first use): consecutive leaves that are
contiguous in CDR as in the ln layout merge into one slice copy, padding is precomputed.  So
a sample without strings is a fixed list of slice copies joined once, and only strings make
positions depend on the data.  Bytes are copied, never converted: floats (NaN payloads,
-0.0) round-trip bit for bit.
"""

from __future__ import annotations

import struct as _struct
import threading
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from .errors import CdrError
from .types import RosType, load_md, md_types, schema_text, search_dirs

if TYPE_CHECKING:
    from ln_generate import Struct

HEADER = b"\x00\x01\x00\x00"  # CDR_LE encapsulation, options 0
MAX_TRAILING = 3  # padding some DDS writers add after the data (to a multiple of 4)
_U32 = _struct.Struct("<I")


@dataclass(frozen=True)
class _Leaf:
    ln_offset: int
    size: int  # bytes in the ln layout (for a string: its N)
    align: int  # CDR alignment; 0 marks a char[N] string
    path: str  # the ln field, for errors: "flange.position", "names[2].text"


@dataclass
class _Plan:
    """A block laid out from a start position p with p % 8 == residue."""

    enc: list[tuple[bytes, int, int]]  # (padding before, ln offset, length)
    dec: list[tuple[int, int]]  # (offset from the block's start, length)
    size: int  # CDR bytes of the block, its padding included
    spans: list[tuple[int, int, str]]  # (start, end) from the block's start, field path


@dataclass
class _Block:
    leaves: list[_Leaf]
    plans: dict[int, _Plan] = field(default_factory=dict)

    def plan(self, residue: int) -> _Plan:
        p = self.plans.get(residue)
        if p is None:
            p = self.plans[residue] = self._lay_out(residue)
        return p

    def _lay_out(self, residue: int) -> _Plan:
        runs: list[list[int]] = []  # [padding, cdr position, ln offset, length]
        spans = []
        pos = residue
        for leaf in self.leaves:
            at = -(-pos // leaf.align) * leaf.align
            if runs and at == pos and runs[-1][2] + runs[-1][3] == leaf.ln_offset:
                runs[-1][3] += leaf.size
            else:
                runs.append([at - pos, at, leaf.ln_offset, leaf.size])
            spans.append((at - residue, at - residue + leaf.size, leaf.path))
            pos = at + leaf.size
        return _Plan([(bytes(pad), ln, n) for pad, _, ln, n in runs],
                     [(at - residue, n) for _, at, _, n in runs], pos - residue, spans)


def _leaves(struct: Struct, base: int, prefix: str) -> list[_Leaf]:
    from ln_generate import Struct

    out: list[_Leaf] = []
    for f in struct.fields:
        at, path = base + f.offset, prefix + f.name
        if isinstance(f.type, Struct):
            if f.kind == "array":
                for i in range(f.count):
                    out += _leaves(f.type, at + i * f.type.size, f"{path}[{i}].")
            else:
                out += _leaves(f.type, at, path + ".")
        elif f.type.kind == "char" and f.kind == "array":
            out.append(_Leaf(at, f.count, 0, path))
        else:
            out.append(_Leaf(at, f.size, f.type.size, path))
    return out


class CdrCodec:
    """Encodes the raw ln bytes of one md's samples as CDR and back (see the module doc).
    Thread-safe: plans are added once per start residue and never changed."""

    def __init__(self, md_name: str, types: list[RosType], struct: Struct,
                 layout_hash: int = 0) -> None:
        self.md_name = md_name
        self.layout_hash = layout_hash  # the md's ln layout hash, to check against a sender's
        self.types = types
        self.type_name = types[0].name
        self.schema_text = schema_text(types)
        self.message_size = struct.size
        self._hash = ""
        self._steps: list[tuple[_Block, _Leaf | None]] = []
        block: list[_Leaf] = []
        for leaf in _leaves(struct, 0, ""):
            if leaf.align:
                block.append(leaf)
            else:
                self._steps.append((_Block(block), leaf))
                block = []
        self._steps.append((_Block(block), None))
        self._steps[0][0].plan(0)

    @property
    def type_hash(self) -> str:
        """The RIHS01 hash of the type (computed on first use)."""
        if not self._hash:
            from .rihs01 import hash_types

            self._hash = hash_types(self.types)
        return self._hash

    def encode(self, raw: Any) -> bytes:
        """The CDR bytes (encapsulation header first) of one sample in the ln layout."""
        mv = memoryview(raw).cast("B")
        if mv.nbytes != self.message_size:
            raise CdrError(f"md '{self.md_name}': a sample is {self.message_size} bytes, "
                           f"not {mv.nbytes}")
        pieces = [HEADER]
        pos = 0  # from the end of the header, where CDR alignment counts from
        for block, string in self._steps:
            plan = block.plan(pos & 7)
            for pad, at, n in plan.enc:
                pieces.append(pad)
                pieces.append(mv[at:at + n])
            pos += plan.size
            if string is None:
                break
            text = bytes(mv[string.ln_offset:string.ln_offset + string.size])
            k = text.find(0)
            k = string.size if k < 0 else k
            pad = -pos & 3
            pieces += (bytes(pad), _U32.pack(k + 1), text[:k], b"\x00")
            pos += pad + 5 + k
        return b"".join(pieces)

    def decode(self, data: Any) -> bytes:
        """The ln layout of one CDR sample (char[N] zero padded); CdrError with the byte
        offset and the field for bytes that are not one."""
        mv = memoryview(data).cast("B")
        end = mv.nbytes
        if end < 4:
            raise self._error(0, f"{end} bytes: shorter than the CDR encapsulation header")
        if mv[0] != 0 or mv[1] != 1:
            raise self._error(0, f"encapsulation {bytes(mv[:2]).hex(' ')} is not "
                                 "little-endian CDR (00 01)")
        pieces: list[Any] = []
        pos = 4
        for block, string in self._steps:
            plan = block.plan((pos - 4) & 7)
            if pos + plan.size > end:
                raise self._short(plan, pos, end)
            for at, n in plan.dec:
                pieces.append(mv[pos + at:pos + at + n])
            pos += plan.size
            if string is None:
                break
            pos, text = self._string(mv, pos + (-(pos - 4) & 3), end, string)
            pieces += (text, bytes(string.size - len(text)))
        if end - pos > MAX_TRAILING:
            raise self._error(pos, f"{end - pos} bytes follow the end of the sample")
        return b"".join(pieces)

    def _string(self, mv: memoryview, pos: int, end: int, leaf: _Leaf) -> tuple[int, Any]:
        if pos + 4 > end:
            raise self._error(end, f"the data ends before the string length of field "
                                   f"'{leaf.path}' (bytes {pos}..{pos + 4})")
        (length,) = _U32.unpack_from(mv, pos)
        if not length:  # some writers send "" as length 0
            return pos + 4, b""
        if length - 1 > leaf.size:
            raise self._error(pos, f"field '{leaf.path}' is a string of {length - 1} bytes, "
                                   f"longer than its char[{leaf.size}]")
        stop = pos + 4 + length
        if stop > end:
            raise self._error(end, f"the data ends inside the string of field '{leaf.path}' "
                                   f"(bytes {pos}..{stop})")
        if mv[stop - 1]:
            raise self._error(stop - 1, f"the string of field '{leaf.path}' does not end "
                                        "with a NUL")
        return stop, mv[pos + 4:stop - 1]

    def _short(self, plan: _Plan, pos: int, end: int) -> CdrError:
        for start, stop, path in plan.spans:
            if pos + stop > end:
                return self._error(end, f"the data ends before the end of field '{path}' "
                                        f"(bytes {pos + start}..{pos + stop})")
        return self._error(end, "the data ends early")  # not reached: spans cover the block

    def _error(self, offset: int, what: str) -> CdrError:
        return CdrError(f"CDR sample of md '{self.md_name}': at byte {offset}: {what}")


_cache: dict[tuple[str, tuple[str, ...]], CdrCodec] = {}
_lock = threading.Lock()


def codec(md_name: str, md_dirs: list[str] | None = None) -> CdrCodec:
    """The CdrCodec of md `md_name` (md lookup as md_loader; one per md and directories)."""
    key = (md_name, tuple(search_dirs(md_dirs)))
    with _lock:
        c = _cache.get(key)
    if c is None:
        md = load_md(md_name, list(key[1]))
        c = CdrCodec(md.name, md_types(md), md.struct, md.layout_hash)
        with _lock:
            c = _cache.setdefault(key, c)
    return c
