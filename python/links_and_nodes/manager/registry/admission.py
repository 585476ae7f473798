"""Who may be a client of this manager (docs/security.md, "Client admission to the manager"):
a loopback connection is judged by its peer's credentials (the uid the kernel gives for the
client's end of the connection by sock_diag, else in /proc/net/tcp{,6}; the groups of that
user from the user database), every
other one by the client key proofs of the CHALLENGE/AUTH exchange, computed exactly as
libln/src/client_auth.c does.  No I/O but reading /proc and the user database."""

from __future__ import annotations

import grp
import hmac
import ipaddress
import os
import pwd
import secrets
import socket
import struct
from dataclasses import dataclass

from ...tools.client_key import CLIENT_LABEL, KEY_BYTES, MANAGER_LABEL, SESSION_LABEL, mac

KEY_HINT = ("set LN_CLIENT_KEY_FILE to a copy of the instance's client key, or install it "
            "as ~/.config/links_and_nodes/client.key (mode 0600)")


class Refused(Exception):
    """The client is not admitted; the text says why, for the client and the log."""


def _resolve(items: list[str], lookup: str) -> frozenset[int]:
    """Numbers of users (lookup "user") or groups ("group") given by name or number;
    ValueError naming an unknown one."""
    numbers = set()
    for item in items:
        if item.isdigit():
            numbers.add(int(item))
            continue
        try:
            numbers.add(pwd.getpwnam(item).pw_uid if lookup == "user"
                        else grp.getgrnam(item).gr_gid)
        except KeyError:
            raise ValueError(f"client_{'uids' if lookup == 'user' else 'gids'}: no {lookup} "
                             f"named '{item}' on this host") from None
    return frozenset(numbers)


# sock_diag (linux/sock_diag.h, linux/inet_diag.h): ask the kernel for one TCP socket by
# its addresses, which costs the same however many sockets the host has (reading
# /proc/net/tcp, the fallback, grows with them, TIME_WAIT ones included).
_NETLINK_SOCK_DIAG = 4
_SOCK_DIAG_BY_FAMILY = 20
_NLM_F_REQUEST = 1
_NLMSG_ERROR = 2
_ALL_STATES = 0xFFFFFFFF
_NO_COOKIE = 0xFFFFFFFF
_HEADER = struct.Struct("=IHHII")  # nlmsghdr
_REQUEST = struct.Struct("=BBBBI")  # inet_diag_req_v2 before its socket id
_SOCKID = struct.Struct(">HH16s16s")  # ports and addresses, network order
_SOCKID_TAIL = struct.Struct("=III")  # interface, cookie
_MSG = struct.Struct("=BBBB48sIIIII")  # inet_diag_msg: ... uid, inode


def _unmapped(host: str) -> ipaddress.IPv4Address | ipaddress.IPv6Address:
    ip = ipaddress.ip_address(host.split("%", 1)[0])
    mapped = getattr(ip, "ipv4_mapped", None)
    return mapped if mapped is not None else ip


def _diag_uid(local: tuple[str, int], peer: tuple[str, int]) -> int | None:
    """The uid of the socket whose source is `peer` and destination `local` (the client's
    end), asked of the kernel by sock_diag; None if it does not say."""
    src, dst = _unmapped(peer[0]), _unmapped(local[0])
    family = socket.AF_INET if src.version == 4 else socket.AF_INET6
    sockid = (_SOCKID.pack(peer[1], local[1], src.packed.ljust(16, b"\0"),
                           dst.packed.ljust(16, b"\0"))
              + _SOCKID_TAIL.pack(0, _NO_COOKIE, _NO_COOKIE))
    body = _REQUEST.pack(family, socket.IPPROTO_TCP, 0, 0, _ALL_STATES) + sockid
    request = _HEADER.pack(_HEADER.size + len(body), _SOCK_DIAG_BY_FAMILY, _NLM_F_REQUEST,
                           1, 0) + body
    with socket.socket(socket.AF_NETLINK, socket.SOCK_DGRAM, _NETLINK_SOCK_DIAG) as nl:
        nl.settimeout(1.0)
        nl.sendto(request, (0, 0))
        answer = nl.recv(8192)
    if len(answer) < _HEADER.size + _MSG.size:
        return None
    _, kind, _, _, _ = _HEADER.unpack_from(answer)
    if kind == _NLMSG_ERROR:
        return None
    fields = _MSG.unpack_from(answer, _HEADER.size)
    return int(fields[8])


def _proc_address(host: str, port: int) -> str:
    """How /proc/net/tcp{,6} writes an address: the address's 32-bit words in host order
    as hex, a colon, the port as hex."""
    ip = ipaddress.ip_address(host.split("%", 1)[0])
    words = struct.unpack(f"={len(ip.packed) // 4}I", ip.packed)
    return "".join(f"{w:08X}" for w in words) + f":{port:04X}"


def _proc_uid(local: tuple[str, int], peer: tuple[str, int]) -> int | None:
    """The same from /proc/net/tcp{,6}: the line with the client's address as its local
    and ours as its remote one."""
    family = "tcp6" if ":" in peer[0] else "tcp"
    theirs, ours = _proc_address(*peer[:2]), _proc_address(*local[:2])
    try:
        with open(f"/proc/net/{family}", encoding="ascii") as table:
            next(table, None)
            for line in table:
                fields = line.split()
                if len(fields) > 7 and fields[1] == theirs and fields[2] == ours:
                    return int(fields[7])
    except OSError:
        return None
    return None


def peer_uid(local: tuple[str, int], peer: tuple[str, int]) -> int | None:
    """The uid owning the client's end of a loopback TCP connection whose manager end is
    `local` and client end `peer`; None if the kernel does not tell."""
    try:
        uid = _diag_uid(local, peer)
    except OSError:
        uid = None
    return uid if uid is not None else _proc_uid(local, peer)


def is_loopback(host: str) -> bool:
    try:
        ip = ipaddress.ip_address(host)
    except ValueError:
        return False
    mapped = getattr(ip, "ipv4_mapped", None)
    return bool(ip.is_loopback or (mapped is not None and mapped.is_loopback))


def _user(uid: int) -> str:
    try:
        return f"user {uid} ({pwd.getpwuid(uid).pw_name})"
    except KeyError:
        return f"user {uid}"


def _groups(uid: int) -> set[int]:
    try:
        entry = pwd.getpwuid(uid)
    except KeyError:
        return set()
    return set(os.getgrouplist(entry.pw_name, entry.pw_gid))


@dataclass(frozen=True)
class Verdict:
    """The decision before any key: admitted (with how, for the log) or a key is needed."""

    admitted: bool
    how: str


class Admission:
    """The instance's admission settings: `key` (client_key_file's key, None: no key
    admission), `uids`/`gids` as configured (None: not restricted)."""

    def __init__(self, instance: str, key: bytes | None = None, uids: list[str] | None = None,
                 gids: list[str] | None = None) -> None:
        self.instance = instance
        self.key = key
        self.uids = _resolve(uids, "user") if uids is not None else None
        self.gids = _resolve(gids, "group") if gids is not None else None
        lists = [f"client_uids: {' '.join(uids)}" if uids is not None else "",
                 f"client_gids: {' '.join(gids)}" if gids is not None else ""]
        self._lists = "; ".join(x for x in lists if x)
        self.own_uid = os.geteuid()

    @property
    def restricted(self) -> bool:
        return self.uids is not None or self.gids is not None

    def judge(self, sock: socket.socket | None) -> Verdict:
        """Admit a connection by its peer's credentials, or say that it needs the key;
        Refused if it may not be a client at all."""
        if sock is None or sock.family == socket.AF_UNIX:  # not a TCP peer: not remote
            return Verdict(True, "local socket")
        if self.key is None and not self.restricted:  # nothing to check: as before
            return Verdict(True, "open")
        local, peer = sock.getsockname(), sock.getpeername()
        uid = peer_uid(local, peer) if is_loopback(peer[0]) else None
        if uid is not None:
            return self._judge_local(uid)
        where = "an unknown local user" if is_loopback(peer[0]) else "a remote host"
        if self.key is not None:
            return Verdict(False, "key")
        raise Refused(f"a client from {where} is not admitted by instance {self.instance} "
                      f"({self._lists}; no client_key_file admits others)")

    def _judge_local(self, uid: int) -> Verdict:
        if self.restricted:
            if uid in (self.uids or ()) or _groups(uid) & (self.gids or set()):
                return Verdict(True, f"{_user(uid)}")
            raise Refused(f"{_user(uid)} is not admitted by instance {self.instance} "
                          f"({self._lists})")
        if self.key is None or uid == self.own_uid:
            return Verdict(True, _user(uid))
        return Verdict(False, "key")

    def challenge(self) -> bytes:
        """A fresh manager nonce."""
        return secrets.token_bytes(KEY_BYTES)

    def verify(self, name: str, manager_nonce: bytes, client_nonce_hex: str,
               proof_hex: str) -> tuple[bytes, bytes]:
        """(the manager's proof, the session key) for a client `name` (as in its HELLO)
        whose AUTH proves the key; Refused otherwise."""
        assert self.key is not None
        if not proof_hex:
            raise Refused(f"instance {self.instance} admits client {name!r} only with its "
                          f"client key, and the client has none: {KEY_HINT}")
        try:
            client_nonce = bytes.fromhex(client_nonce_hex)
            proof = bytes.fromhex(proof_hex)
        except ValueError:
            raise Refused("AUTH nonce or proof is not hex") from None
        if len(client_nonce) != KEY_BYTES or len(proof) != KEY_BYTES:
            raise Refused("AUTH nonce or proof is not 32 bytes")
        expected = mac(self.key, CLIENT_LABEL, self.instance, name, manager_nonce, client_nonce)
        if not hmac.compare_digest(expected, proof):
            raise Refused(f"client {name!r} proved a wrong client key for instance "
                          f"{self.instance}: its key file differs from the instance's "
                          "client_key_file")
        return (mac(self.key, MANAGER_LABEL, self.instance, name, manager_nonce, client_nonce),
                mac(self.key, SESSION_LABEL, self.instance, name, manager_nonce, client_nonce))
