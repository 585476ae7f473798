"""Admission by key, the parts both sides share (docs/security.md, "Client admission to the
manager"): the proofs' HMAC-SHA256 (libln/src/client_auth.c computes the same bytes), the
client key file of the Python tools that speak the protocol themselves, and their answer
to CHALLENGE.  The manager's side is manager/registry/admission.py."""

from __future__ import annotations

import hashlib
import hmac
import os
import secrets
import socket
import stat
from collections.abc import Callable
from pathlib import Path

from .. import __version__
from . import protocol as p
from .framing import receive

KEY_BYTES = 32
CLIENT_LABEL = "ln client proof v1"
MANAGER_LABEL = "ln manager proof v1"
SESSION_LABEL = "ln session key v1"


class ClientKeyError(Exception):
    """The client key is unusable, or the manager could not prove it; the text says which."""


def mac(key: bytes, label: str, instance: str, name: str, manager_nonce: bytes,
        client_nonce: bytes) -> bytes:
    """HMAC-SHA256 under `key` of label, 0, instance, 0, client name, 0, both nonces."""
    message = b"\0".join(s.encode() for s in (label, instance, name, ""))
    return hmac.new(key, message + manager_nonce + client_nonce, hashlib.sha256).digest()


def key_path() -> tuple[Path, bool]:
    """$LN_CLIENT_KEY_FILE (True: named), else ~/.config/links_and_nodes/client.key."""
    env = os.environ.get("LN_CLIENT_KEY_FILE")
    if env:
        return Path(env), True
    return Path.home() / ".config" / "links_and_nodes" / "client.key", False


def load_key() -> bytes | None:
    """The client key, None if there is no key file; ClientKeyError if it is unusable (the
    daemon key file's checks: a private regular file of ours, 64 hex digits)."""
    path, named = key_path()
    try:
        fd = os.open(path, os.O_RDONLY | os.O_CLOEXEC | os.O_NOCTTY)
    except FileNotFoundError:
        if not named:
            return None
        raise ClientKeyError(f"cannot open client key file '{path}': no such file") from None
    except OSError as exc:
        raise ClientKeyError(f"cannot open client key file '{path}': {exc.strerror}") from None
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode) or st.st_uid != os.geteuid() or st.st_mode & 0o077:
            raise ClientKeyError(f"client key file '{path}' must be a regular file of uid "
                                 f"{os.geteuid()} with mode 0600")
        data = os.read(fd, 130)
    finally:
        os.close(fd)
    text = data[:-1] if data.endswith(b"\n") else data
    try:
        key = bytes.fromhex(text.decode("ascii"))
    except ValueError:
        key = b""
    if len(key) != KEY_BYTES:
        raise ClientKeyError(f"client key file '{path}' holds no valid key: it must contain "
                             "exactly 64 hex digits (32 bytes), optionally followed by a "
                             "newline")
    return key


def prove(challenge: p.Message, name: str) -> tuple[p.Message, Callable[[p.Message], None]]:
    """The AUTH answering `challenge` for client `name` (as in its HELLO), and the check of
    the manager's AUTH_OK, which raises ClientKeyError if the manager did not prove the key.
    Without a key file AUTH carries no proof (the manager then refuses, saying why)."""
    instance = challenge.instance_name  # type: ignore[attr-defined]
    try:
        theirs = bytes.fromhex(challenge.nonce)  # type: ignore[attr-defined]
    except ValueError:
        theirs = b""
    if len(theirs) != KEY_BYTES:
        raise ClientKeyError("CHALLENGE nonce is not 64 hex digits")
    key = load_key()
    mine = secrets.token_bytes(KEY_BYTES)
    proof = mac(key, CLIENT_LABEL, instance, name, theirs, mine).hex() if key else ""

    def check(auth_ok: p.Message) -> None:
        assert key is not None
        expected = mac(key, MANAGER_LABEL, instance, name, theirs, mine)
        try:
            got = bytes.fromhex(auth_ok.proof)  # type: ignore[attr-defined]
        except ValueError:
            got = b""
        if not hmac.compare_digest(expected, got):
            raise ClientKeyError(f"the manager failed to prove the client key of instance "
                                 f"{instance!r}: it is not that instance's manager or its key "
                                 "differs")

    return p.Auth(mine.hex(), proof), check


def greet(sock: socket.socket, name: str, error: type[Exception]) -> p.Message:
    """HELLO as client `name` on a connected blocking socket, a CHALLENGE answered with the
    client key and the manager's AUTH_OK checked; the manager's last answer (WELCOME, or the
    ERROR that refused the client).  `error` (with the reason) for a key problem or a broken
    frame; socket errors and timeouts pass."""
    sock.sendall(p.encode(p.Hello(p.MAGIC, p.VERSION, os.getpid(), name, __version__, "")))
    reply = receive(sock, error)
    if not isinstance(reply, p.Challenge):
        return reply
    try:
        auth, check = prove(reply, name)
        sock.sendall(p.encode(auth))
        reply = receive(sock, error)
        # With a proof sent only AUTH_OK or the refusal may follow (as libln's handshake).
        proved = bool(auth.proof)  # type: ignore[attr-defined]
        if not isinstance(reply, p.Error) and isinstance(reply, p.AuthOk) != proved:
            raise ClientKeyError(
                f"the manager did not prove the client key (it answered AUTH with "
                f"{reply.TYPE.name})" if proved else "AUTH_OK to a client that sent no proof")
        if isinstance(reply, p.AuthOk):
            check(reply)
            reply = receive(sock, error)
    except ClientKeyError as exc:
        raise error(str(exc)) from None
    return reply
