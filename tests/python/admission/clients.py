"""The admission tests' client: libln's own (C, through the ctypes layer), so that what is
tested is the handshake every language binding runs; a refusal is the LnError the binding
raises, with libln's text."""

from __future__ import annotations

import ctypes

from links_and_nodes import _clientlib as C

SIZE = 16
HASH = 0x0123456789ABCDEF
MD = b"test/pair"
TIMEOUT = 30.0  # seconds; an upper bound, never reached by a passing test


class Client:
    def __init__(self, address: str, name: str) -> None:
        opts = C.ClientOptions()
        C.ln_client_options_init(ctypes.byref(opts))
        opts.manager = address.encode()
        opts.timeout = TIMEOUT
        opts.flags |= C.LN_CLIENT_NO_RECONNECT
        handle = ctypes.c_void_p()
        C.ln_client_create(ctypes.byref(handle), name.encode(), ctypes.byref(opts))
        self.handle = handle

    def _port(self, fn: object, topic: str) -> ctypes.c_void_p:
        opts = C.PortOptions()
        C.ln_port_options_init(ctypes.byref(opts))
        port = ctypes.c_void_p()
        fn(self.handle, ctypes.byref(port), topic.encode(), MD, HASH, SIZE,  # type: ignore[operator]
           ctypes.byref(opts))
        return port

    def publish(self, topic: str) -> ctypes.c_void_p:
        return self._port(C.ln_publish, topic)

    def subscribe(self, topic: str) -> ctypes.c_void_p:
        return self._port(C.ln_subscribe, topic)

    def close(self) -> None:
        C.ln_client_destroy(self.handle)

    def __enter__(self) -> Client:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
