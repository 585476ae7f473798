"""ctypes declarations of libln_pull's NDN codec (ln/ndn.h) for the tests: decode and encode
through the product's C codec, to compare it with python-ndn and with ndn_wire.py.  The
product's Python side only needs the consumer (links_and_nodes._pull_lib)."""

from __future__ import annotations

import ctypes

from links_and_nodes._pull_lib import lib

c_u8p = ctypes.POINTER(ctypes.c_uint8)


class Bytes(ctypes.Structure):
    _fields_ = [("data", c_u8p), ("size", ctypes.c_size_t)]

    def get(self) -> bytes:
        return ctypes.string_at(self.data, self.size) if self.size else b""


class Interest(ctypes.Structure):
    _fields_ = [("name", Bytes), ("nonce", ctypes.c_uint32), ("lifetime_ms", ctypes.c_uint32),
                ("has_nonce", ctypes.c_uint8), ("can_be_prefix", ctypes.c_uint8),
                ("must_be_fresh", ctypes.c_uint8), ("has_hop_limit", ctypes.c_uint8),
                ("hop_limit", ctypes.c_uint8), ("app_parameters", Bytes)]


class Data(ctypes.Structure):
    _fields_ = [("name", Bytes), ("content_type", ctypes.c_uint32),
                ("freshness_ms", ctypes.c_uint32), ("content", Bytes),
                ("signature_type", ctypes.c_uint32), ("key_locator", Bytes),
                ("signature_value", Bytes), ("signed_portion", Bytes)]


class Packet(ctypes.Structure):
    _fields_ = [("type", ctypes.c_uint32), ("lp", ctypes.c_uint8), ("lp_nack", ctypes.c_uint8),
                ("nack_reason", ctypes.c_uint32), ("pit_token", Bytes),
                ("interest", Interest), ("data", Data)]


class Signer(ctypes.Structure):
    _fields_ = [("type", ctypes.c_uint32), ("key", c_u8p), ("key_size", ctypes.c_size_t),
                ("key_name", Bytes)]


class PullContent(ctypes.Structure):
    _fields_ = [("latest_seq", ctypes.c_uint64), ("publish_us", ctypes.c_uint64),
                ("period_us", ctypes.c_uint64), ("payload", Bytes)]


STRUCTS = {"ln_ndn_bytes": Bytes, "ln_ndn_interest": Interest, "ln_ndn_data": Data,
           "ln_ndn_packet": Packet, "ln_ndn_signer": Signer,
           "ln_ndn_pull_content": PullContent}


def _f(name: str, restype: object, *argtypes: object) -> object:
    func = getattr(lib, name)
    func.restype, func.argtypes = restype, list(argtypes)
    return func


ln_ndn_decode = _f("ln_ndn_decode", ctypes.c_int, ctypes.c_char_p, ctypes.c_size_t,
                   ctypes.POINTER(Packet))
ln_ndn_encode_interest = _f("ln_ndn_encode_interest", ctypes.c_int, c_u8p, ctypes.c_size_t,
                            ctypes.POINTER(Interest))
ln_ndn_encode_data = _f("ln_ndn_encode_data", ctypes.c_int, c_u8p, ctypes.c_size_t,
                        ctypes.POINTER(Data), ctypes.POINTER(Signer))
ln_ndn_verify = _f("ln_ndn_verify", ctypes.c_int, ctypes.POINTER(Data), ctypes.POINTER(Signer))
ln_ndn_name_from_uri = _f("ln_ndn_name_from_uri", ctypes.c_int, c_u8p, ctypes.c_size_t,
                          ctypes.c_char_p)
ln_ndn_name_to_uri = _f("ln_ndn_name_to_uri", ctypes.c_int, ctypes.c_char_p, ctypes.c_size_t,
                        Bytes)
ln_ndn_encode_pull_content = _f("ln_ndn_encode_pull_content", ctypes.c_int, c_u8p,
                                ctypes.c_size_t, ctypes.POINTER(PullContent))
ln_ndn_decode_pull_content = _f("ln_ndn_decode_pull_content", ctypes.c_int, Bytes,
                                ctypes.POINTER(PullContent))


class Decoded:
    """A decoded packet that keeps its buffer alive (the views point into it)."""

    def __init__(self, buf: bytes) -> None:
        self.buf = ctypes.create_string_buffer(buf, len(buf))
        self.packet = Packet()
        self.rc = ln_ndn_decode(ctypes.cast(self.buf, ctypes.c_char_p), len(buf),
                                ctypes.byref(self.packet))


def view(b: bytes) -> tuple[Bytes, object]:
    """A Bytes view of `b` and the buffer to keep alive with it."""
    buf = (ctypes.c_uint8 * max(len(b), 1)).from_buffer_copy(b.ljust(1, b"\0"))
    return Bytes(ctypes.cast(buf, c_u8p), len(b)), buf


def name_from_uri(uri: str) -> bytes:
    out = (ctypes.c_uint8 * 512)()
    n = ln_ndn_name_from_uri(out, 512, uri.encode())
    assert n >= 0, n
    return bytes(out[:n])


def encode_data(name: bytes, content: bytes, freshness_ms: int = 0, content_type: int = 0,
                key: bytes = b"") -> bytes:
    d = Data()
    d.name, keep1 = view(name)
    d.content, keep2 = view(content)
    d.freshness_ms, d.content_type = freshness_ms, content_type
    s = Signer()
    kbuf = (ctypes.c_uint8 * max(len(key), 1)).from_buffer_copy(key.ljust(1, b"\0"))
    s.type, s.key, s.key_size = (4 if key else 0), ctypes.cast(kbuf, c_u8p), len(key)
    out = (ctypes.c_uint8 * 9000)()
    n = ln_ndn_encode_data(out, 9000, ctypes.byref(d), ctypes.byref(s))
    assert n >= 0, n
    del keep1, keep2
    return bytes(out[:n])


def encode_interest(name: bytes, nonce: int, lifetime_ms: int = 4000,
                    can_be_prefix: bool = False, must_be_fresh: bool = False) -> bytes:
    i = Interest()
    i.name, keep = view(name)
    i.nonce, i.lifetime_ms, i.has_nonce = nonce, lifetime_ms, 1
    i.can_be_prefix, i.must_be_fresh = int(can_be_prefix), int(must_be_fresh)
    out = (ctypes.c_uint8 * 512)()
    n = ln_ndn_encode_interest(out, 512, ctypes.byref(i))
    assert n >= 0, n
    del keep
    return bytes(out[:n])


def encode_pull_content(latest: int, publish_us: int, period_us: int,
                        payload: bytes | None) -> bytes:
    c = PullContent(latest, publish_us, period_us)
    keep = None
    if payload is not None:
        c.payload, keep = view(payload)
    out = (ctypes.c_uint8 * 9000)()
    n = ln_ndn_encode_pull_content(out, 9000, ctypes.byref(c))
    assert n >= 0, n
    del keep
    return bytes(out[:n])
