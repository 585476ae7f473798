"""The buffers of the full-payload mode of the Python topic benchmarks (py_ln.py,
py_iox2.py): a whole sample is copied with one ctypes.memmove from a bytearray into a loan,
and from a borrowed sample into a bytearray; the first and last 8 bytes carry the counter,
so a torn sample shows."""

from __future__ import annotations

import ctypes
import sys

U64 = ctypes.c_uint64


class Payload:
    """A sample-sized bytearray outside the transport, with the views memmove and the
    counter stamp need (made once: nothing is allocated per sample)."""

    __slots__ = ("buf", "view", "head", "tail", "size")

    def __init__(self, size: int) -> None:
        self.size = size
        self.buf = bytearray(b"\x5a" * size)  # every page touched before timing
        self.view = (ctypes.c_char * size).from_buffer(self.buf)
        self.head = U64.from_buffer(self.buf, 0)
        self.tail = U64.from_buffer(self.buf, size - 8)

    def stamp(self, value: int) -> None:
        self.head.value = value
        self.tail.value = value

    def into(self, address: int) -> None:
        """The whole buffer into the sample at `address` (a loan)."""
        ctypes.memmove(address, self.view, self.size)

    def take(self, address: int, who: str) -> int:
        """The whole sample at `address` (a borrow) into the buffer; its counter."""
        ctypes.memmove(self.view, address, self.size)
        head, tail = self.head.value, self.tail.value
        if head != tail:
            sys.exit(f"{who}: torn sample {head}/{tail}")
        return head
