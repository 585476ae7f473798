"""The Python parameter block (docs/parameters.md): `ln.parameter_block(clnt, "gains")` or
`clnt.get_parameter_block("gains")`, parameters added with `add()`, `register()`, then
`update()` from the program's loop.

    blk = clnt.get_parameter_block("gains")
    kp = blk.add("kp", "double", 7, default=[50.0] * 7, min=0, max=1000,
                 description="stiffness (Nm/rad)")
    blk.register()
    while True:
        blk.update()             # overrides that arrived since the last call
        use(kp.value)            # the override, else kp.input

libln checks and serves the overrides on its own service thread; the values live in
buffers this module owns (the program writes `p.input`, update() writes the output)."""

from __future__ import annotations

import ctypes
import logging
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from . import _param_lib as P
from ._handles import run_close_hooks

if TYPE_CHECKING:
    from ._client import client

__all__ = ["parameter", "parameter_block"]

_log = logging.getLogger("links_and_nodes.parameters")

# md primitive (and alias) -> (canonical name, numpy dtype)
_TYPES = {"char": ("char", "S1"), "int8_t": ("int8_t", "<i1"), "uint8_t": ("uint8_t", "<u1"),
          "int16_t": ("int16_t", "<i2"), "short": ("int16_t", "<i2"),
          "uint16_t": ("uint16_t", "<u2"), "int32_t": ("int32_t", "<i4"),
          "int": ("int32_t", "<i4"), "uint32_t": ("uint32_t", "<u4"),
          "int64_t": ("int64_t", "<i8"), "uint64_t": ("uint64_t", "<u8"),
          "float": ("float", "<f4"), "float32_t": ("float", "<f4"),
          "double": ("double", "<f8"), "float64_t": ("double", "<f8")}

# validator(name, value) -> None/True: accept; False or a reason (str): refuse
Validator = Callable[[str, Any], Any]


class parameter:  # noqa: N801 - the LN naming
    """One parameter of a block: `input` (a numpy array the program writes; None for a
    parameter without input), `value` (what update() made of it: the override, else the
    input), `changed` (in the last update)."""

    def __init__(self, block: parameter_block, index: int, name: str, type_name: str,
                 count: int, has_input: bool, default: Any) -> None:
        self.block = block
        self.index = index
        self.name = name
        self.type, dtype = _TYPES[type_name]
        self.count = count
        self._dtype = np.dtype(dtype)
        size = self._dtype.itemsize * count
        self._out = ctypes.create_string_buffer(size)
        self._in = ctypes.create_string_buffer(size) if has_input else None
        initial = self._encode(default)
        ctypes.memmove(self._in if self._in is not None else self._out, initial, size)
        if self._in is not None:
            ctypes.memmove(self._out, initial, size)

    def _encode(self, value: Any) -> bytes:
        size = self._dtype.itemsize * self.count
        if value is None:
            return bytes(size)
        if self.type == "char":
            raw = value.encode() if isinstance(value, str) else bytes(value)
            if len(raw) > self.count:
                raise ValueError(f"parameter {self.name!r}: {len(raw)} bytes do not fit in "
                                 f"char[{self.count}]")
            return raw.ljust(self.count, b"\0")
        array = np.asarray(value, dtype=self._dtype)
        if self.count == 1 and array.shape in ((), (1,)):
            return array.reshape(1).tobytes()
        if array.shape != (self.count,):
            raise ValueError(f"parameter {self.name!r}: expected {self.count} values, got "
                             f"shape {array.shape}")
        return array.tobytes()

    def decode(self, raw: bytes) -> Any:
        """Bytes of this parameter as a Python value: str for char, a number for one
        element, else a numpy array (a copy)."""
        if self.type == "char":
            return raw.split(b"\0", 1)[0].decode("utf-8", "surrogateescape")
        array = np.frombuffer(raw, dtype=self._dtype, count=self.count).copy()
        return array[0].item() if self.count == 1 else array

    @property
    def input(self) -> Any:
        """The program's variable: a writable numpy view (bytes for char), or None."""
        if self._in is None:
            return None
        if self.type == "char":
            return self._in
        return np.frombuffer(self._in, dtype=self._dtype, count=self.count)

    @input.setter
    def input(self, value: Any) -> None:
        if self._in is None:
            raise ValueError(f"parameter {self.name!r} has no input")
        ctypes.memmove(self._in, self._encode(value), len(self._in))

    @property
    def value(self) -> Any:
        """What update() made of it: the override, else the input (or the default)."""
        return self.decode(self._out.raw)

    @property
    def changed(self) -> bool:
        return self.block._changed(self.index)

    def __repr__(self) -> str:
        return f"<parameter {self.block.name}.{self.name} {self.type}[{self.count}]>"


class parameter_block:  # noqa: N801 - the LN naming
    """A block of parameters of `clnt` (`name`: 1..63 bytes of A-Z a-z 0-9 _ -), served as
    service "<client>.parameters.<name>" once registered; see the module's docstring."""

    def __init__(self, clnt: client, name: str) -> None:
        handle = ctypes.c_void_p()
        P.ln_parameter_block_create(clnt.handle, ctypes.byref(handle), name.encode())
        self.client = clnt
        self.name = name
        self._handle: int | None = handle.value
        self.parameters: dict[str, parameter] = {}
        self._validator: Validator | None = None
        self._callback: Any = None  # the ctypes callback: alive as long as libln may call it
        self._close_hooks: list[Callable[[], None]] = []  # its waitset attachments (_handles)
        clnt._providers.append(self)  # type: ignore[arg-type] - forgotten and kept alive
        from ._client import _pool_clients

        _pool_clients.add(clnt)  # its validator may run in a pool thread: close before exit

    @property
    def handle(self) -> int:
        if self._handle is None:
            raise ValueError(f"parameter block {self.name!r} is closed")
        return self._handle

    def add(self, name: str, type: str = "double", count: int = 1, default: Any = None, *,
            description: str = "", min: float | None = None, max: float | None = None,
            read_only: bool = False, input: bool = True) -> parameter:
        """Add parameter `name` of md primitive `type` with `count` elements (char[count]
        holds a string), starting at `default` (zeros if None).  With `input` (default) the
        program sets its value through `p.input`, else the value without an override is
        the default.  min/max bound every element."""
        if type not in _TYPES:
            raise ValueError(f"parameter {name!r}: {type!r} is not an md primitive type "
                             f"({', '.join(sorted(set(t for t, _ in _TYPES.values())))})")
        if count < 1:
            raise ValueError(f"parameter {name!r}: count must be at least 1")
        p = parameter(self, len(self.parameters), name, type, count, input, default)
        desc = P.ParameterDesc()
        desc.name = name.encode()
        desc.type = p.type.encode()
        desc.count = count
        desc.description = description.encode()
        desc.input = ctypes.addressof(p._in) if p._in is not None else None
        desc.output = ctypes.addressof(p._out)
        if min is not None:
            desc.flags |= P.LN_PARAMETER_MIN
            desc.min = float(min)
        if max is not None:
            desc.flags |= P.LN_PARAMETER_MAX
            desc.max = float(max)
        if read_only:
            desc.flags |= P.LN_PARAMETER_READ_ONLY
        index = P.ln_parameter_block_add(self.handle, ctypes.byref(desc))
        p.index = index
        self.parameters[name] = p
        return p

    def set_validator(self, validator: Validator | None) -> None:
        """validator(name, value) runs on libln's service thread for every value about to
        be taken (after the type and range checks); value as `p.value` gives it.  Return
        None or True to accept, False or a reason (str) to refuse; an exception refuses with
        its text."""
        self._validator = validator
        self._callback = P.VALIDATOR(self._validate) if validator is not None else None
        P.ln_parameter_block_set_validator(self.handle, self._callback or P.VALIDATOR(),
                                           None)

    def _validate(self, _blk: int, _index: int, name: bytes, value: int, reason: int,
                  size: int, _user: int) -> int:
        try:
            p = self.parameters[name.decode()]
            raw = ctypes.string_at(value, p._dtype.itemsize * p.count)
            verdict = self._validator(p.name, p.decode(raw)) if self._validator else None
        except Exception as exc:  # noqa: BLE001 - a refusal with its text
            _log.info("validator of %s.%s failed", self.name, name.decode(), exc_info=True)
            verdict = f"{type(exc).__name__}: {exc}"
        if verdict is None or verdict is True or verdict == "":
            return 0
        text = verdict if isinstance(verdict, str) else "refused by the validator"
        raw_text = text.encode("utf-8", "replace")[:max(size - 1, 0)]
        ctypes.memmove(reason, raw_text + b"\0", len(raw_text) + 1)
        return 1

    def register(self) -> None:
        """Take the initial overrides of $LN_PARAMETERS and register the block's service;
        no add() after this."""
        P.ln_parameter_block_register(self.handle)

    def update(self) -> int:
        """The loop's update point: takes the overrides that arrived since the last call and
        writes every value; returns how many parameters changed their override."""
        return int(P.ln_parameter_block_update(self.handle))

    def _changed(self, index: int) -> bool:
        return P.ln_parameter_block_changed(self.handle, index) == 1

    @property
    def service_name(self) -> str:
        return P.ln_parameter_block_service_name(self.handle).decode()

    def __getitem__(self, name: str) -> Any:
        return self.parameters[name].value

    def values(self) -> dict[str, Any]:
        """Every parameter's value as of the last update()."""
        return {name: p.value for name, p in self.parameters.items()}

    def changed(self) -> list[str]:
        """The parameters that changed in the last update()."""
        return [name for name, p in self.parameters.items() if p.changed]

    def _forget(self) -> None:
        """The client is closing: libln destroys the block with it."""
        run_close_hooks(self)
        self._handle = None

    def close(self) -> None:
        """Unregister the block's service and free it (the client does it when closed)."""
        if self._handle is not None:
            run_close_hooks(self)
        handle, self._handle = self._handle, None
        if handle is not None:
            P.ln_parameter_block_destroy(handle)
        if self in self.client._providers:
            self.client._providers.remove(self)  # type: ignore[arg-type]

    def __enter__(self) -> parameter_block:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
