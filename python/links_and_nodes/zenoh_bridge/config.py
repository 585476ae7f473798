"""ln_zenoh's configuration: the rules saying which topics and services go which way, read from
a TOML or JSON file (docs/zenoh.md, "Configuration") and from the command line's specs
`PATTERN[,queued[=N]][,latest][,rate=HZ][,remote=PREFIX][,timeout=S]`.  The first rule whose
pattern matches a name decides (file rules first, then the command line's)."""

from __future__ import annotations

import json
import math
import tomllib
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

from .wire import bad_name, matches

MAX_BUFFERS = 1024  # libln's limit per port
DEFAULT_BUFFERS = 64
DIRECTIONS = ("out", "in")
MODES = ("peer", "client")
NATIVE = ("auto", "on", "off")


class ConfigError(ValueError):
    """A configuration that cannot work; the text names the setting."""


@dataclass
class TopicRule:
    """Topics matching `pattern` (a name or fnmatch pattern) go `direction`: "out" is
    links_and_nodes → Zenoh, "in" is Zenoh (from the bridge with prefix `remote`) → here."""

    pattern: str
    direction: str
    queued: bool = False  # False: latest mode (newest sample wins), True: every sample
    buffers: int = DEFAULT_BUFFERS  # queue depth of a queued topic
    rate: float | None = None  # most samples per second, None: no limit
    remote: str | None = None  # "in": the other bridge's prefix (default: BridgeConfig.remote)

    @property
    def depth(self) -> int:
        return self.buffers if self.queued else 1


@dataclass
class ServiceRule:
    """Services matching `pattern`: "out" serves a local service to Zenoh, "in" provides the
    services of the bridge with prefix `remote` here; `timeout`: seconds a forwarded call may
    take."""

    pattern: str
    direction: str
    remote: str | None = None
    timeout: float = 10.0


@dataclass
class BridgeConfig:
    prefix: str | None = None  # None: ln/<instance>
    mode: str = "peer"
    connect: list[str] = field(default_factory=list)
    listen: list[str] = field(default_factory=list)
    zenoh_config: str | None = None  # a Zenoh config file (JSON5) the settings above go into
    remote: str | None = None  # default prefix of the other bridge for "in" rules
    topics: list[TopicRule] = field(default_factory=list)
    services: list[ServiceRule] = field(default_factory=list)
    ros2: bool = False
    ros2_domain: int = 0
    manager: str | None = None
    name: str = "ln_zenoh"
    md_dirs: list[str] = field(default_factory=list)
    stats_interval: float = 0.0  # seconds between statistics lines, 0: on SIGUSR1 and exit
    stats_file: str | None = None
    poll: float = 1.0  # seconds between looks at the manager's topic and service lists
    native: str = "auto"  # the native core for topic samples: auto (if found), on, off
    batch: bool = True  # batches between two bridges' native cores (docs/zenoh.md)

    def topic_rule(self, name: str, direction: str) -> TopicRule | None:
        for rule in self.topics:
            if rule.direction == direction and matches(name, rule.pattern):
                return rule
        return None

    def service_rule(self, name: str, direction: str) -> ServiceRule | None:
        for rule in self.services:
            if rule.direction == direction and matches(name, rule.pattern):
                return rule
        return None

    def check(self) -> None:
        """ConfigError for settings that cannot work together."""
        if self.native not in NATIVE:
            raise ConfigError(f"native must be one of {', '.join(NATIVE)}, not {self.native!r}")
        if self.mode not in MODES:
            raise ConfigError(f"mode must be one of {', '.join(MODES)}, not {self.mode!r}")
        if self.mode == "client" and not self.connect and not self.zenoh_config:
            raise ConfigError("mode client needs a connect endpoint (a Zenoh router or peer)")
        for prefix in [self.prefix, self.remote] + [r.remote for r in self.topics + self.services]:
            if prefix is not None and (why := bad_name(prefix)):
                raise ConfigError(f"prefix {prefix!r} cannot be a key expression: {why}")
        self._check_rules()
        if not self.topics and not self.services:
            raise ConfigError("nothing to bridge: give topics or services (--out, --in, "
                              "--service-out, --service-in or a config file)")

    def _check_rules(self) -> None:
        """ConfigError for a rule that cannot work; inbound rules get the default remote."""
        for rule in self.topics + self.services:
            if rule.direction not in DIRECTIONS:
                raise ConfigError(f"{rule.pattern}: direction must be out or in, "
                                  f"not {rule.direction!r}")
            if rule.direction == "in" and rule.remote is None:
                if self.remote is None:
                    raise ConfigError(f"{rule.pattern}: an inbound rule needs the other "
                                      "bridge's prefix (remote = PREFIX, or --remote)")
                rule.remote = self.remote
        for topic in self.topics:
            if not 2 <= topic.buffers <= MAX_BUFFERS:
                raise ConfigError(f"{topic.pattern}: buffers must be 2..{MAX_BUFFERS}")
            if topic.rate is not None and not (topic.rate > 0 and math.isfinite(topic.rate)):
                raise ConfigError(f"{topic.pattern}: rate must be a positive number")
        for service in self.services:
            if not service.timeout > 0:
                raise ConfigError(f"{service.pattern}: timeout must be positive")


# ---- the config file ---------------------------------------------------------------------------

_TOPIC_KEYS = {"match", "direction", "queue", "buffers", "rate", "remote"}
_SERVICE_KEYS = {"match", "direction", "remote", "timeout"}
_SCALARS = {f.name for f in fields(BridgeConfig)} - {"topics", "services"}


def load_file(path: str | Path) -> BridgeConfig:
    """A BridgeConfig from a .toml or .json file; ConfigError naming the file and the key."""
    path = Path(path)
    try:
        text = path.read_text()
        data = json.loads(text) if path.suffix == ".json" else tomllib.loads(text)
    except (OSError, ValueError) as exc:
        raise ConfigError(f"{path}: {exc}") from None
    try:
        return from_dict(data)
    except ConfigError as exc:
        raise ConfigError(f"{path}: {exc}") from None


def from_dict(data: dict[str, Any]) -> BridgeConfig:
    config = BridgeConfig()
    for key, value in data.items():
        if key == "topics":
            config.topics += [rule for t in _tables(key, value) for rule in _topic_rules(t)]
        elif key == "services":
            config.services += [rule for s in _tables(key, value) for rule in _service_rules(s)]
        elif key in _SCALARS:
            setattr(config, key, _typed(key, value, getattr(config, key)))
        else:
            raise ConfigError(f"unknown setting {key!r}")
    return config


def _tables(key: str, value: Any) -> list[dict[str, Any]]:
    if not isinstance(value, list) or not all(isinstance(v, dict) for v in value):
        raise ConfigError(f"{key} must be a list of tables ([[{key}]])")
    return value


def _typed(key: str, value: Any, default: Any) -> Any:
    if isinstance(default, list):
        if isinstance(value, str):
            value = [value]
        if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
            raise ConfigError(f"{key} must be a list of strings")
        return value
    if isinstance(default, bool):
        if not isinstance(value, bool):
            raise ConfigError(f"{key} must be true or false")
        return value
    if isinstance(default, (int, float)) and not isinstance(value, bool):
        if isinstance(value, (int, float)):
            return type(default)(value)
        raise ConfigError(f"{key} must be a number")
    if not isinstance(value, str):
        raise ConfigError(f"{key} must be a string")
    return value


def _patterns(table: dict[str, Any]) -> list[str]:
    match = table.get("match")
    patterns = [match] if isinstance(match, str) else match
    if not patterns or not all(isinstance(p, str) and p for p in patterns):
        raise ConfigError(f"a rule needs match = PATTERN or a list of them: {table}")
    return patterns


def _unknown(table: dict[str, Any], allowed: set[str]) -> None:
    extra = set(table) - allowed
    if extra:
        raise ConfigError(f"unknown key(s) {', '.join(sorted(extra))} in rule {table}")


def _topic_rules(table: dict[str, Any]) -> list[TopicRule]:
    _unknown(table, _TOPIC_KEYS)
    queue = table.get("queue", "latest")
    if queue not in ("latest", "queued"):
        raise ConfigError(f"queue must be latest or queued, not {queue!r}")
    rate = table.get("rate")
    buffers = table.get("buffers", DEFAULT_BUFFERS)
    if not isinstance(buffers, int) or isinstance(buffers, bool):
        raise ConfigError(f"buffers must be a whole number, not {buffers!r}")
    if rate is not None and (isinstance(rate, bool) or not isinstance(rate, (int, float))):
        raise ConfigError(f"rate must be a number, not {rate!r}")
    return [TopicRule(p, str(table.get("direction", "")), queue == "queued", buffers,
                      None if rate is None else float(rate), table.get("remote"))
            for p in _patterns(table)]


def _service_rules(table: dict[str, Any]) -> list[ServiceRule]:
    _unknown(table, _SERVICE_KEYS)
    timeout = table.get("timeout", 10.0)
    if isinstance(timeout, bool) or not isinstance(timeout, (int, float)):
        raise ConfigError(f"timeout must be a number, not {timeout!r}")
    return [ServiceRule(p, str(table.get("direction", "")), table.get("remote"), float(timeout))
            for p in _patterns(table)]


# ---- command-line specs ------------------------------------------------------------------------

def _spec_items(spec: str) -> tuple[str, dict[str, str | None]]:
    pattern, *options = spec.split(",")
    if not pattern:
        raise ConfigError(f"{spec!r}: no pattern before the options")
    items: dict[str, str | None] = {}
    for option in options:
        key, eq, value = option.partition("=")
        items[key.strip()] = value.strip() if eq else None
    return pattern, items


def _number(spec: str, key: str, value: str | None, kind: type) -> Any:
    try:
        return kind(value)
    except (TypeError, ValueError):
        raise ConfigError(f"{spec!r}: {key} needs a number ({key}=N)") from None


def topic_spec(spec: str, direction: str) -> TopicRule:
    """`PATTERN[,queued[=N]][,latest][,rate=HZ][,remote=PREFIX]` as a TopicRule."""
    pattern, items = _spec_items(spec)
    rule = TopicRule(pattern, direction)
    for key, value in items.items():
        if key == "queued":
            rule.queued = True
            if value is not None:
                rule.buffers = _number(spec, key, value, int)
        elif key == "latest" and value is None:
            rule.queued = False
        elif key == "rate":
            rule.rate = _number(spec, key, value, float)
        elif key == "remote" and value:
            rule.remote = value
        else:
            raise ConfigError(f"{spec!r}: unknown option {key!r} (queued[=N], latest, "
                              "rate=HZ, remote=PREFIX)")
    return rule


def service_spec(spec: str, direction: str) -> ServiceRule:
    """`PATTERN[,remote=PREFIX][,timeout=S]` as a ServiceRule."""
    pattern, items = _spec_items(spec)
    rule = ServiceRule(pattern, direction)
    for key, value in items.items():
        if key == "remote" and value:
            rule.remote = value
        elif key == "timeout":
            rule.timeout = _number(spec, key, value, float)
        else:
            raise ConfigError(f"{spec!r}: unknown option {key!r} (remote=PREFIX, timeout=S)")
    return rule
