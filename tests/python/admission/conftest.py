"""Fixtures of the client admission tests (docs/security.md, "Client admission to the
manager"): `admission` writes a test's key files and `.lnc` (unique instance, its own runtime
directory) and starts ln_manager on it; every manager is stopped with SIGTERM after the test
and must exit 0.  `remote_host` is an address of this host that is not loopback, through
which a client reaches the manager as a remote host's client would."""

from __future__ import annotations

import secrets
import socket
import sys
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[3]
sys.path.insert(0, str(REPO / "tests" / "python" / "manager"))

from mgrproc import WAIT, Manager, require_manager_library, unique_instance  # noqa: E402


def write_key(path: Path, key: bytes | None = None, mode: int = 0o600) -> Path:
    path.write_text((key or secrets.token_bytes(32)).hex() + "\n")
    path.chmod(mode)
    return path


@dataclass
class Admission:
    tmp: Path
    instance: str = field(default_factory=unique_instance)
    managers: list[Manager] = field(default_factory=list)

    def start(self, instance_keys: str = "", access: str = "",
              host: str = "127.0.0.1") -> Manager:
        """ln_manager -c on a file with `instance_keys` in its instance section and
        `access` as its access section (if given), listening on `host`."""
        config = self.tmp / f"{self.instance}.lnc"
        text = f"instance\nname: {self.instance}\nmanager: :1\n{instance_keys}\n"
        if access:
            text += f"\naccess\n{access}\n"
        config.write_text(text)
        manager = Manager(self.instance, self.tmp / "run",
                          self.tmp / f"manager-{len(self.managers)}.log",
                          ["-c", str(config), "--no-console", "--host", host,
                           "--daemon-key-file", str(self.tmp / "daemon.key")])
        self.managers.append(manager)
        return manager.wait_ready()


@pytest.fixture
def admission(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[Admission]:
    # No key of the user running the tests may leak in: each test names its own.
    monkeypatch.delenv("LN_CLIENT_KEY_FILE", raising=False)
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    require_manager_library()  # here, not at import: the parsing tests load no native code
    lab = Admission(tmp_path)
    yield lab
    problems = []
    for manager in lab.managers:
        status = manager.stop()
        if status != 0:
            problems.append(f"ln_manager exited with {status}; log:\n{manager.log()}")
        if manager.proc.stdout is not None:
            manager.proc.stdout.close()
    assert not problems, "\n".join(problems)


@pytest.fixture
def remote_host() -> str:
    """This host's address on the interface of its default route (not loopback)."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        try:
            probe.connect(("192.0.2.1", 9))  # no packet is sent: this only picks a route
            address = probe.getsockname()[0]
        except OSError as exc:
            pytest.skip(f"this host has no route off loopback: {exc}")
    if address.startswith("127."):
        pytest.skip("this host has no address but loopback")
    return address


__all__ = ["WAIT", "Admission", "write_key"]
