"""Self-signed certificates for the web UI's TLS tests, made with the openssl command line
(P-256 keys, valid two days, names in subjectAltName) in the test's own directory, with the
SPKI hash a Chromium is told to trust (--ignore-certificate-errors-spki-list)."""

from __future__ import annotations

import base64
import hashlib
import subprocess
from dataclasses import dataclass
from pathlib import Path

from buildtree import missing_test_tool

LIMIT = 60.0


@dataclass
class Cert:
    cert: Path
    key: Path

    @property
    def spki(self) -> str:
        """base64(SHA-256(SubjectPublicKeyInfo)), as Chromium's SPKI list wants it."""
        pub = _openssl("x509", "-in", str(self.cert), "-pubkey", "-noout")
        der = subprocess.run(["openssl", "pkey", "-pubin", "-outform", "der"], input=pub,
                             capture_output=True, check=True, timeout=LIMIT).stdout
        return base64.b64encode(hashlib.sha256(der).digest()).decode()


def _openssl(*argv: str) -> bytes:
    try:
        done = subprocess.run(["openssl", *argv], capture_output=True, timeout=LIMIT)
    except FileNotFoundError:
        missing_test_tool("the openssl command line tool")
    assert done.returncode == 0, done.stderr.decode(errors="replace")
    return done.stdout


def self_signed(directory: Path, name: str = "webui",
                names: tuple[str, ...] = ("IP:127.0.0.1", "DNS:localhost")) -> Cert:
    """A new certificate and key (mode 600) for `names` under `directory`."""
    directory.mkdir(parents=True, exist_ok=True)
    cert, key = directory / f"{name}.crt", directory / f"{name}.key"
    _openssl("req", "-x509", "-newkey", "ec", "-pkeyopt", "ec_paramgen_curve:P-256",
             "-nodes", "-days", "2", "-subj", f"/CN={names[0].split(':', 1)[1]}",
             "-addext", f"subjectAltName={','.join(names)}", "-keyout", str(key),
             "-out", str(cert))
    key.chmod(0o600)
    return Cert(cert, key)
