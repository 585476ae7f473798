"""Who may use the web UI (docs/webui.md, "Security"): the auth file of `user
password-hash` lines (scrypt hashes, refused if group or other may read the file), the
sessions a successful HTTP Basic login opens (random token in an HttpOnly SameSite=Strict
cookie, Secure over TLS, an expiry, a CSRF token per session) and `ln_manager webui-passwd
USER`."""

from __future__ import annotations

import base64
import binascii
import functools
import getpass
import hashlib
import hmac
import os
import secrets
import stat
import sys
import time
from dataclasses import dataclass
from pathlib import Path

SCRYPT_N, SCRYPT_R, SCRYPT_P = 1 << 14, 8, 1  # 16 MiB of memory per check
SCRYPT_MAXMEM = 64 << 20
SESSION_SECONDS = 12 * 3600
MAX_SESSIONS = 256
COOKIE = "lnm_session"


class AuthFileError(Exception):
    """The auth file cannot be used; the text says why and what to do."""


def hash_password(password: str, *, n: int = SCRYPT_N, r: int = SCRYPT_R,
                  p: int = SCRYPT_P) -> str:
    """`scrypt$N$r$p$SALT$HASH` (salt and hash in unpadded base64)."""
    salt = secrets.token_bytes(16)
    key = hashlib.scrypt(password.encode(), salt=salt, n=n, r=r, p=p, maxmem=SCRYPT_MAXMEM,
                         dklen=32)
    return f"scrypt${n}${r}${p}${_b64(salt)}${_b64(key)}"


def verify_password(password: str, stored: str) -> bool:
    """Whether `password` matches a hash_password() string; False for a malformed one."""
    parts = stored.split("$")
    if len(parts) != 6 or parts[0] != "scrypt":
        return False
    try:
        n, r, p = int(parts[1]), int(parts[2]), int(parts[3])
        salt, key = _unb64(parts[4]), _unb64(parts[5])
        if not (2 <= n <= 1 << 20 and 1 <= r <= 32 and 1 <= p <= 16 and key):
            return False
        got = hashlib.scrypt(password.encode(), salt=salt, n=n, r=r, p=p,
                             maxmem=SCRYPT_MAXMEM, dklen=len(key))
    except (ValueError, binascii.Error, MemoryError):
        return False
    return hmac.compare_digest(got, key)


def _b64(data: bytes) -> str:
    return base64.b64encode(data).decode().rstrip("=")


def _unb64(text: str) -> bytes:
    return base64.b64decode(text + "=" * (-len(text) % 4), validate=True)


def load_auth_file(path: str | Path) -> dict[str, str]:
    """user -> password hash; AuthFileError if the file is missing, readable by group or
    other, or has a malformed line (with its line number)."""
    path = Path(path)
    try:
        st = path.stat()
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise AuthFileError(f"web UI auth file {path}: {exc.strerror or exc}") from None
    except UnicodeDecodeError:
        raise AuthFileError(f"web UI auth file {path}: not UTF-8 text") from None
    if st.st_mode & (stat.S_IRWXG | stat.S_IRWXO):
        raise AuthFileError(f"web UI auth file {path}: group or other may access it (mode "
                            f"{stat.S_IMODE(st.st_mode):04o}); refused: run "
                            f"'chmod 600 {path}'")
    users: dict[str, str] = {}
    for number, line in enumerate(text.splitlines(), 1):
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        words = line.split()
        if len(words) != 2 or not words[1].startswith("scrypt$") or words[1].count("$") != 5:
            raise AuthFileError(f"{path}:{number}: expected 'USER scrypt$N$r$p$SALT$HASH' "
                                "(make one with 'ln_manager webui-passwd USER')")
        users[words[0]] = words[1]
    if not users:
        raise AuthFileError(f"web UI auth file {path}: no users")
    return users


def basic_credentials(header: str) -> tuple[str, str] | None:
    """(user, password) of an `Authorization: Basic ...` value; None if it is not one."""
    scheme, _, value = header.strip().partition(" ")
    if scheme.lower() != "basic":
        return None
    try:
        user, sep, password = base64.b64decode(value.strip(), validate=True).decode(
            "utf-8").partition(":")
    except (ValueError, binascii.Error, UnicodeDecodeError):
        return None
    return (user, password) if sep else None


@dataclass
class Session:
    token: str
    csrf: str
    user: str
    expires: float  # time.monotonic()


class Sessions:
    """The open sessions; with `users` None (no auth file) anyone reaching the loopback
    address gets one without a password.  `secure`: the cookie is sent over HTTPS only."""

    def __init__(self, users: dict[str, str] | None, lifetime: float = SESSION_SECONDS,
                 *, secure: bool = False) -> None:
        self.users = users
        self.lifetime = lifetime
        self.secure = secure
        self._open: dict[str, Session] = {}
        if users is not None:
            _dummy()  # here, not at the first login: that one must cost what the others do

    @property
    def open_access(self) -> bool:
        return self.users is None

    def login(self, user: str, password: str) -> Session | None:
        """A new session if the credentials are right (checked in constant time per user
        known or not), else None."""
        stored = (self.users or {}).get(user)
        ok = verify_password(password, stored or _dummy())
        if stored is None or not ok:
            return None
        return self.open(user)

    def open(self, user: str) -> Session:
        self._expire()
        while len(self._open) >= MAX_SESSIONS:  # the oldest goes
            del self._open[next(iter(self._open))]
        session = Session(secrets.token_urlsafe(32), secrets.token_urlsafe(32), user,
                          time.monotonic() + self.lifetime)
        self._open[session.token] = session
        return session

    def get(self, token: str | None) -> Session | None:
        if not token:
            return None
        session = self._open.get(token)
        if session is None:
            return None
        if session.expires <= time.monotonic():
            del self._open[token]
            return None
        return session

    def close(self, token: str) -> None:
        self._open.pop(token, None)

    def _expire(self) -> None:
        now = time.monotonic()
        for token in [t for t, s in self._open.items() if s.expires <= now]:
            del self._open[token]

    def cookie(self, session: Session) -> str:
        return (f"{COOKIE}={session.token}; Path=/; HttpOnly; SameSite=Strict; "
                f"{'Secure; ' if self.secure else ''}Max-Age={int(self.lifetime)}")

    def cleared_cookie(self) -> str:
        """The Set-Cookie value that removes the session cookie (at logout)."""
        return f"{COOKIE}=; Path=/; Max-Age=0; HttpOnly; SameSite=Strict" + \
            ("; Secure" if self.secure else "")


@functools.cache
def _dummy() -> str:
    """The hash an unknown user's password is checked against, so that it costs as much as a
    known one's; made once, when the first Sessions with users is (not at import: scrypt
    takes tens of milliseconds, and a manager without the web UI's auth never needs it)."""
    return hash_password("", n=SCRYPT_N)


def csrf_ok(session: Session, token: object) -> bool:
    return isinstance(token, str) and hmac.compare_digest(token.encode(), session.csrf.encode())


def passwd_main(argv: list[str]) -> int:
    """`ln_manager webui-passwd USER`: print an auth file line for USER, the password read
    from stdin (one line) or, on a terminal, asked twice."""
    if len(argv) != 1 or argv[0].startswith("-") or not argv[0].isprintable() \
            or any(c.isspace() for c in argv[0]):
        print("usage: ln_manager webui-passwd USER   (password from stdin or a prompt; "
              "append the printed line to the auth file, mode 600)", file=sys.stderr)
        return 2
    if sys.stdin.isatty():
        password = getpass.getpass("password: ")
        if getpass.getpass("again: ") != password:
            print("ln_manager webui-passwd: the passwords differ", file=sys.stderr)
            return 1
    else:
        password = sys.stdin.readline().rstrip("\r\n")
    if not password:
        print("ln_manager webui-passwd: empty password refused", file=sys.stderr)
        return 1
    print(f"{argv[0]} {hash_password(password)}")
    return 0


def auth_file_from(config_path: str | None) -> str | None:
    """LNM_WEBUI_AUTH_FILE wins over the instance section's webui_auth_file."""
    return os.environ.get("LNM_WEBUI_AUTH_FILE") or config_path
