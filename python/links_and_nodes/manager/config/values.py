"""Parsers of typed `.lnc` values (numbers, durations, sizes, signals, policies, CPU
lists, resource limits, ...).  Each takes an evaluated Value and the key it belongs to,
and raises LineError pointing at the bad part."""

from __future__ import annotations

import ipaddress
import re
import signal

from ... import addresses
from ...naming import topic_name_problem
from .errors import LineError, Problem, did_you_mean
from .model import OnLimit, Policy, ResourceLimit, Restart, Watchdog
from .text import Value, split_value

_INT_RE = re.compile(r"[+-]?[0-9]+\Z")
_FLOAT_RE = re.compile(r"[+-]?([0-9]+(\.[0-9]*)?|\.[0-9]+)([eE][+-]?[0-9]+)?\Z")
_DURATION_RE = re.compile(r"([0-9]+(?:\.[0-9]*)?|\.[0-9]+)\s*(ms|s|min|h)?\Z")
_SIZE_RE = re.compile(r"([0-9]+)\s*(?:([kKmMgGtT])(?:i?[bB])?|[bB])?\Z")
_ENV_NAME_RE = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
_DURATION_UNITS = {None: 1.0, "s": 1.0, "ms": 0.001, "min": 60.0, "h": 3600.0}
_SIZE_UNITS = {None: 1, "k": 1 << 10, "m": 1 << 20, "g": 1 << 30, "t": 1 << 40}
MAX_CPU = 1023  # highest CPU number of a cpu_set_t
RLIMITS = ("as", "core", "cpu", "data", "fsize", "locks", "memlock", "msgqueue", "nice",
           "nofile", "nproc", "rss", "rtprio", "rttime", "sigpending", "stack")
_POLICY_WORDS = {"OTHER": Policy.OTHER, "FIFO": Policy.FIFO, "RR": Policy.RR}


def fail(v: Value, message: str, offset: int = 0) -> LineError:
    return LineError.at(v.at(offset), message)


def parse_int(v: Value, key: str, lo: int | None = None, hi: int | None = None) -> int:
    if not _INT_RE.match(v.text):
        raise fail(v, f"'{key}' must be an integer, got '{v.text}'")
    n = int(v.text)
    check_range(v, key, n, lo, hi)
    return n


def parse_float(v: Value, key: str, lo: float | None = None, *, above: bool = False) -> float:
    """A decimal number; with `above` it must be greater than `lo`, else at least `lo`."""
    if not _FLOAT_RE.match(v.text):
        raise fail(v, f"'{key}' must be a number, got '{v.text}'")
    x = float(v.text)
    if lo is not None and (x <= lo if above else x < lo):
        raise fail(v, f"'{key}' must be {'greater than' if above else 'at least'} {lo:g}, "
                      f"got {v.text}")
    return x


def check_range(v: Value, key: str, n: int, lo: int | None, hi: int | None,
                why: str = "") -> None:
    if lo is not None and hi is not None and not lo <= n <= hi:
        raise fail(v, f"'{key}' must be between {lo} and {hi}{why}, got {n}")
    if lo is not None and n < lo:
        raise fail(v, f"'{key}' must be at least {lo}{why}, got {n}")
    if hi is not None and n > hi:
        raise fail(v, f"'{key}' must be at most {hi}{why}, got {n}")


def parse_duration(v: Value, key: str) -> float:
    """Seconds: `2.5`, `2.5s`, `500ms`, `1min`, `1h`."""
    m = _DURATION_RE.match(v.text)
    if m is None:
        raise fail(v, f"'{key}' must be a duration like 2.5, 500ms or 1min, got '{v.text}'")
    return float(m.group(1)) * _DURATION_UNITS[m.group(2)]


def parse_size(v: Value, key: str) -> int:
    """Bytes: `4096`, `512K`, `10M`, `1G` (also `KB`/`KiB`; all powers of 1024)."""
    m = _SIZE_RE.match(v.text)
    if m is None:
        raise fail(v, f"'{key}' must be a size like 4096, 512K, 10M or 1G, got '{v.text}'")
    unit = m.group(2).lower() if m.group(2) else None
    return int(m.group(1)) * _SIZE_UNITS[unit]


def parse_signal(v: Value, key: str) -> int:
    """A signal name (`SIGINT`, `INT`, case-insensitive) or number."""
    text = v.text.strip()
    if _INT_RE.match(text):
        n = int(text)
        if n not in {int(s) for s in signal.valid_signals()}:
            raise fail(v, f"'{key}': {n} is not a signal number of this system")
        return n
    name = text.upper()
    name = name if name.startswith("SIG") else "SIG" + name
    names = {s.name: int(s) for s in signal.Signals if not s.name.startswith("SIG_")}
    if name not in names:
        raise fail(v, f"unknown signal '{text}' for '{key}'{did_you_mean(name, names)}")
    return names[name]


def parse_policy(v: Value, key: str) -> Policy:
    word = v.text.strip().upper().removeprefix("SCHED_")
    if word not in _POLICY_WORDS:
        hint = did_you_mean(v.text.upper(), [p.value for p in Policy])
        raise fail(v, f"unknown scheduling policy '{v.text}' "
                      f"(expected SCHED_OTHER, SCHED_FIFO or SCHED_RR){hint}")
    return _POLICY_WORDS[word]


def parse_restart(v: Value, key: str) -> Restart:
    word = v.text.strip().lower()
    for r in Restart:
        if word == r.value:
            return r
    hint = did_you_mean(word, [r.value for r in Restart])
    raise fail(v, f"'{key}' must be never, on-failure or always, got '{v.text}'{hint}")


def parse_on_limit(v: Value, key: str) -> OnLimit:
    word = v.text.strip().lower()
    for r in OnLimit:
        if word == r.value:
            return r
    hint = did_you_mean(word, [r.value for r in OnLimit])
    raise fail(v, f"'{key}' must be warn or restart, got '{v.text}'{hint}")


def parse_affinity(v: Value, key: str) -> list[int]:
    """CPU numbers: `0,2,4-7` (sorted, without repeats)."""
    cpus: set[int] = set()
    items = split_value(v)
    if not items:
        raise fail(v, f"'{key}' needs CPU numbers like 0,2,4-7")
    problems = []
    for item in items:
        m = re.match(r"([0-9]+)\s*(?:-\s*([0-9]+))?\Z", item.text)
        if m is None:
            problems.append(Problem(item.loc, f"bad CPU '{item.text}' in '{key}' "
                                              "(expected N or N-M)"))
            continue
        lo, hi = int(m.group(1)), int(m.group(2) or m.group(1))
        if lo > hi or hi > MAX_CPU:
            problems.append(Problem(item.loc, f"bad CPU range '{item.text}' in '{key}' "
                                              f"(CPUs are 0..{MAX_CPU}, N-M needs N <= M)"))
            continue
        cpus.update(range(lo, hi + 1))
    if problems:
        raise LineError(problems)
    return sorted(cpus)


def _limit_value(v: Value, text: str, offset: int) -> int | None:
    if text.lower() in ("unlimited", "infinity"):
        return None
    m = _SIZE_RE.match(text)
    if m is None:
        raise fail(v, f"bad resource limit '{text}' (expected a number, a size like 64M, "
                      "or 'unlimited')", offset)
    unit = m.group(2).lower() if m.group(2) else None
    return int(m.group(1)) * _SIZE_UNITS[unit]


def parse_resource_limits(v: Value, key: str) -> list[ResourceLimit]:
    """`NAME:SOFT[:HARD], ...`; NAME is an RLIMIT_ suffix (`nofile`, `RLIMIT_CORE`), the
    limits numbers, sizes (`64M`) or `unlimited`; without HARD both limits are SOFT."""
    limits: dict[str, ResourceLimit] = {}
    problems = []
    items = split_value(v)
    if not items:
        raise fail(v, f"'{key}' needs entries like nofile:1024:4096")
    for item in items:
        parts = item.text.split(":")
        name = parts[0].strip().lower().removeprefix("rlimit_")
        try:
            if len(parts) not in (2, 3):
                raise fail(item, f"resource limit '{item.text}' must be NAME:SOFT or "
                                 "NAME:SOFT:HARD")
            if name not in RLIMITS:
                raise fail(item, f"unknown resource limit '{parts[0].strip()}'"
                                 f"{did_you_mean(name, RLIMITS)}")
            offset = len(parts[0]) + 1
            soft = _limit_value(item, parts[1].strip(), offset)
            hard = soft if len(parts) == 2 else _limit_value(
                item, parts[2].strip(), offset + len(parts[1]) + 1)
            if hard is not None and (soft is None or soft > hard):
                raise fail(item, f"soft limit of '{name}' is above its hard limit")
            limits[name] = ResourceLimit(name, soft, hard)
        except LineError as exc:
            problems.extend(exc.problems)
    if problems:
        raise LineError(problems)
    return list(limits.values())


def parse_topic(v: Value, kind: str) -> str:
    """A topic or service name by the registry's rules."""
    problem = topic_name_problem(v.text, kind)
    if problem:
        raise fail(v, problem)
    return v.text


def parse_watchdog(v: Value, key: str) -> Watchdog:
    """`TOPIC, MIN_HZ`."""
    items = split_value(v)
    if len(items) != 2:
        raise fail(v, f"'{key}' must be 'TOPIC, MIN_HZ', got '{v.text}'")
    parse_topic(items[0], "topic")
    return Watchdog(items[0].text, parse_float(items[1], key + " rate", 0.0, above=True))


def parse_env_entry(v: Value, key: str) -> tuple[str, str]:
    """`NAME=VALUE` (the value may be empty)."""
    name, eq, value = v.text.partition("=")
    if not eq:
        raise fail(v, f"'{key}' entry '{v.text}' must be NAME=VALUE")
    if not _ENV_NAME_RE.match(name):
        raise fail(v, f"bad environment variable name '{name}' in '{key}'")
    return name, value


def split_env_entries(v: Value) -> list[Value]:
    """Several `NAME=VALUE` on one line are separated by a comma and blanks before the next
    NAME=; other commas belong to the value (`OMP_PLACES=0,1`)."""
    items = []
    start = 0
    for m in re.finditer(r",\s+(?=[A-Za-z_][A-Za-z0-9_]*=)", v.text):
        items.append((v.text[start:m.start()], start))
        start = m.end()
    items.append((v.text[start:], start))
    out = []
    for text, offset in items:
        stripped = text.strip()
        if stripped:
            lead = len(text) - len(text.lstrip())
            out.append(Value(stripped, v.at(offset + lead), v.exact))
    return out


def env_name(v: Value, key: str) -> str:
    if not _ENV_NAME_RE.match(v.text):
        raise fail(v, f"bad environment variable name '{v.text}' in '{key}'")
    return v.text


def parse_ip(v: Value, label: str) -> str:
    """An interface address, IPv4 or IPv6; returned in its normal form."""
    try:
        return str(ipaddress.ip_address(v.text))
    except ValueError:
        raise fail(v, f"interface '{label}' needs an IPv4 or IPv6 address, "
                      f"got '{v.text}'") from None


def parse_subnet(v: Value, where: str) -> str:
    """`IP/BITS`, IPv4 (BITS 0..32) or IPv6 (0..128); host bits may be set, as in
    `ip addr` (`10.0.0.7/24` is 10.0.0.0/24).  Returned normalised."""
    address, slash, bits = v.text.rpartition("/")
    try:
        if not slash or not re.match(r"[0-9]{1,3}\Z", bits):
            raise ValueError
        return str(ipaddress.ip_network(f"{ipaddress.ip_address(address)}/{int(bits)}",
                                        strict=False))
    except ValueError:
        raise fail(v, f"bad subnet '{v.text}' in {where} (expected IP/BITS: an IPv4 address "
                      "and 0..32, or an IPv6 address and 0..128)") from None


def parse_address(v: Value, key: str) -> str:
    """`HOST:PORT`, `:PORT` or `[V6HOST]:PORT` (addresses.parse_address), port 1..65535;
    returned as written."""
    try:
        addresses.parse_address(v.text, default_host="")
    except addresses.AddressError as exc:
        if exc.kind in ("form", "port"):
            raise fail(v, f"'{key}' must be HOST:PORT or :PORT with a port of 1..65535, "
                          f"got '{v.text}'") from None
        raise fail(v, f"'{key}': {exc}") from None
    return v.text
