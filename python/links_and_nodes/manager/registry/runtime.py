"""The per-instance runtime directory and the lock in it that makes one manager per
instance: a second manager would otherwise purge the segments of the first one's topics.
The lock is an flock, so the kernel drops it when the manager dies, even by SIGKILL.
Also the clean-up of the Unix sockets that service providers leave in that directory."""

from __future__ import annotations

import fcntl
import os
import stat
from pathlib import Path

from ...naming import SERVICE_SOCKET_NAME

LOCK_NAME = "manager.lock"


class RuntimeDirError(Exception):
    """The runtime directory cannot be used, or another manager holds the lock."""


def _private_dir(path: Path) -> None:
    """Make `path` an existing directory of ours with mode 0700."""
    try:
        try:
            path.mkdir(mode=0o700)
        except FileExistsError:
            pass
        info = path.lstat()
    except OSError as exc:
        raise RuntimeDirError(f"cannot create runtime directory {path}: {exc.strerror}") from None
    if not stat.S_ISDIR(info.st_mode):
        raise RuntimeDirError(f"runtime directory {path} is not a directory (nor may it be "
                              "a symlink)")
    if info.st_uid != os.getuid():
        raise RuntimeDirError(f"runtime directory {path} belongs to uid {info.st_uid}, "
                              f"not to us ({os.getuid()})")
    if stat.S_IMODE(info.st_mode) != 0o700:
        os.chmod(path, 0o700)


def prepare(path: Path) -> Path:
    """Create the runtime directory (and missing parents, each 0700) and return it."""
    missing = []
    for candidate in [path, *path.parents]:
        if candidate.exists():
            break
        missing.append(candidate)
    for directory in reversed(missing[1:]):
        _private_dir(directory)
    # /tmp/ln-<uid> is shared ground: someone else may have created it first.
    if path.parent.name == f"ln-{os.getuid()}" and path.parent not in missing:
        _private_dir(path.parent)
    _private_dir(path)
    return path


class InstanceLock:
    """An exclusive, non-blocking flock on <runtime dir>/manager.lock holding our pid."""

    def __init__(self, directory: Path, instance: str) -> None:
        self.path = directory / LOCK_NAME
        self.instance = instance
        self._fd: int | None = None

    def acquire(self) -> None:
        try:
            fd = os.open(self.path, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o600)
        except OSError as exc:
            raise RuntimeDirError(f"cannot open {self.path}: {exc.strerror}") from None
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = os.read(fd, 32).decode(errors="replace").strip() or "unknown"
            os.close(fd)
            raise RuntimeDirError(f"instance {self.instance!r} is already managed by another "
                                  f"ln_manager (pid {holder}, lock {self.path})") from None
        except OSError as exc:
            os.close(fd)
            raise RuntimeDirError(f"cannot lock {self.path}: {exc.strerror}") from None
        os.ftruncate(fd, 0)
        os.write(fd, f"{os.getpid()}\n".encode())
        self._fd = fd

    def release(self) -> None:
        if self._fd is not None:
            os.ftruncate(self._fd, 0)
            os.close(self._fd)  # closing drops the flock
            self._fd = None

    def __enter__(self) -> InstanceLock:
        self.acquire()
        return self

    def __exit__(self, *exc: object) -> None:
        self.release()


def remove_service_socket(path: str | Path) -> str | None:
    """Unlink a provider's socket: only if its file name is svc.<pid>.<n>.sock and it is a
    socket (not a symlink to one) owned by our uid.  None if it was unlinked, else why it
    was left."""
    path = Path(path)
    if not SERVICE_SOCKET_NAME.match(path.name):
        return "not named svc.<pid>.<n>.sock"
    try:
        info = path.lstat()
    except FileNotFoundError:
        return "no such file"
    except OSError as exc:
        return f"cannot stat it: {exc.strerror}"
    if not stat.S_ISSOCK(info.st_mode):
        return "not a socket"
    if info.st_uid != os.getuid():
        return f"owned by uid {info.st_uid}, not by us ({os.getuid()})"
    try:
        path.unlink()
    except FileNotFoundError:
        return "no such file"
    except OSError as exc:
        return f"cannot unlink it: {exc.strerror}"
    return None


def service_sockets(directory: Path) -> list[str]:
    """Names of the files in `directory` named like provider sockets, sorted."""
    with os.scandir(directory) as entries:
        return sorted(e.name for e in entries if SERVICE_SOCKET_NAME.match(e.name))


def purge_service_sockets(directory: Path, names: list[str] | None = None) -> list[str]:
    """Unlink every provider socket (as remove_service_socket decides) in `directory`, or
    only those of `names`: what killed providers left; the names unlinked."""
    removed = []
    if names is None:
        names = service_sockets(directory)
    for name in names:
        if remove_service_socket(directory / name) is None:
            removed.append(name)
    return removed
