"""The web UI's TLS (docs/webui.md, "TLS"): the server SSLContext of a PEM certificate
(chain) and its private key, TLS 1.2 or newer, checked at start so that an unreadable,
malformed, encrypted, world-readable or mismatched file ends the manager naming it."""

from __future__ import annotations

import ssl
import stat
from pathlib import Path

HSTS = "max-age=31536000"  # one year; sent on the TLS port only (RFC 6797)


class TLSError(Exception):
    """The certificate or key cannot be used; the text names the file and says why."""


def _read(path: str, what: str) -> str:
    try:
        data = Path(path).read_bytes()
    except OSError as exc:
        raise TLSError(f"web UI TLS {what} {path}: {exc.strerror or exc}") from None
    try:
        return data.decode("ascii")
    except UnicodeDecodeError:
        raise TLSError(f"web UI TLS {what} {path}: not a PEM file (DER? convert it with "
                       "'openssl x509 -inform der' or 'openssl pkey -inform der')") from None


def _check_key_mode(path: str) -> None:
    mode = Path(path).stat().st_mode
    if mode & stat.S_IRWXO:
        raise TLSError(f"web UI TLS key {path}: other users may access it (mode "
                       f"{stat.S_IMODE(mode):04o}); refused: run 'chmod o-rwx {path}'")


def _no_password() -> bytes:
    raise TLSError("encrypted")


def server_context(cert: str, key: str) -> ssl.SSLContext:
    """A server context serving `cert` with `key`; TLSError naming the file at fault."""
    if "-----BEGIN CERTIFICATE-----" not in _read(cert, "certificate"):
        raise TLSError(f"web UI TLS certificate {cert}: no '-----BEGIN CERTIFICATE-----' "
                       "block (a PEM certificate is expected)")
    key_text = _read(key, "key")
    if "PRIVATE KEY-----" not in key_text:
        raise TLSError(f"web UI TLS key {key}: no '-----BEGIN ... PRIVATE KEY-----' block "
                       "(a PEM private key is expected)")
    _check_key_mode(key)
    try:  # the certificate alone first, so that a broken one is named as such
        ssl.create_default_context().load_verify_locations(cafile=cert)
    except ssl.SSLError as exc:
        raise TLSError(f"web UI TLS certificate {cert}: not a valid PEM certificate "
                       f"({exc.reason or exc})") from None
    context = ssl.create_default_context(ssl.Purpose.CLIENT_AUTH)
    context.minimum_version = ssl.TLSVersion.TLSv1_2
    context.set_alpn_protocols(["http/1.1"])
    try:
        context.load_cert_chain(cert, key, password=_no_password)
    except TLSError:
        raise TLSError(f"web UI TLS key {key}: encrypted with a passphrase, which the "
                       "manager cannot ask for: decrypt it ('openssl pkey -in KEY -out "
                       "NEW') and keep it mode 600") from None
    except ssl.SSLError as exc:
        reason = exc.reason or str(exc)
        if "KEY_VALUES_MISMATCH" in str(exc) or reason == "KEY_VALUES_MISMATCH":
            raise TLSError(f"web UI TLS key {key} does not belong to the certificate "
                           f"{cert}") from None
        raise TLSError(f"web UI TLS key {key}: not a valid PEM private key ({reason})"
                       ) from None
    return context
