"""The key files the manager and ln_daemon share (docs/daemon.md, "Authentication"): where
the default one is, reading one (refusing a key file others can read) and creating one."""

from __future__ import annotations

import contextlib
import os
import secrets
import stat
from pathlib import Path

from ... import default_ports
from .daemon_wire import KEY_BYTES, DaemonError


class KeyFileError(DaemonError):
    """A key file that is missing, not private or not a key."""


# ---- key files ----------------------------------------------------------------------------


def default_port() -> int:
    """$LN_ARBITER_PORT, else 54376: where ln_daemon listens unless told otherwise
    (default_ports.daemon_port, as DaemonError if the variable is bad)."""
    try:
        return default_ports.daemon_port()
    except ValueError as exc:
        raise DaemonError(str(exc)) from None


def default_key_file() -> Path:
    """$LN_DAEMON_KEY_FILE, else ~/.config/links_and_nodes/daemon.key."""
    env = os.environ.get("LN_DAEMON_KEY_FILE")
    if env:
        return Path(env)
    return Path.home() / ".config" / "links_and_nodes" / "daemon.key"


def read_key_file(path: str | os.PathLike[str]) -> bytes:
    """The 32-byte key of a key file, with the daemon's checks: a regular file of ours,
    nothing for group or others, 64 hex digits and an optional newline."""
    path = os.fspath(path)
    try:
        fd = os.open(path, os.O_RDONLY | os.O_CLOEXEC | os.O_NOCTTY)
    except OSError as e:
        raise KeyFileError(f"cannot open key file '{path}': {e.strerror}") from e
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            raise KeyFileError(f"key file '{path}' is not a regular file")
        if st.st_uid != os.geteuid():
            raise KeyFileError(f"key file '{path}' is owned by uid {st.st_uid}, not by "
                               f"uid {os.geteuid()}")
        if st.st_mode & 0o077:
            raise KeyFileError(f"key file '{path}' is accessible by group or others (mode "
                               f"{stat.S_IMODE(st.st_mode):04o}); it must be private: "
                               f"chmod 600 '{path}'")
        data = os.read(fd, 130)
    finally:
        os.close(fd)
    text = data[:-1] if data.endswith(b"\n") else data
    try:
        if len(text) != 2 * KEY_BYTES:
            raise ValueError
        return bytes.fromhex(text.decode("ascii"))
    except ValueError:
        raise KeyFileError(f"key file '{path}' holds no valid key: it must contain exactly "
                           "64 hex digits (32 bytes), optionally followed by a newline") from None


def create_key_file(path: str | os.PathLike[str]) -> bytes:
    """Write a new random key to `path` (mode 0600; missing parent directories are created
    with mode 0700) and return it.  An existing file is never overwritten."""
    path = Path(path)
    missing = []
    parent = path.parent
    while not parent.exists():
        missing.append(parent)
        parent = parent.parent
    for directory in reversed(missing):
        with contextlib.suppress(FileExistsError):
            directory.mkdir(mode=0o700)
    key = secrets.token_bytes(KEY_BYTES)
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_CLOEXEC, 0o600)
    try:
        os.fchmod(fd, 0o600)
        os.write(fd, key.hex().encode() + b"\n")
    finally:
        os.close(fd)
    return key
