"""The typed model of a loaded `.lnc` configuration: what the parser produces and the
scheduler consumes.  Plain dataclasses, fully resolved: every `%()` expanded, every
template replayed, every name prefixed, every reference checked.  A leaf module."""

from __future__ import annotations

import enum
import fnmatch
import ipaddress
import signal
from dataclasses import dataclass, field

from ... import default_ports, transports

DEFAULT_ARBITER_PORT = default_ports.DAEMON_PORT  # unless LN_ARBITER_PORT says otherwise


@dataclass(frozen=True)
class Location:
    """Where something was written: 1-based line and column."""

    file: str
    line: int
    col: int

    def __str__(self) -> str:
        return f"{self.file}:{self.line}:{self.col}"


class Restart(enum.Enum):
    NEVER = "never"
    ON_FAILURE = "on-failure"
    ALWAYS = "always"


class OnLimit(enum.Enum):
    """What a process over its `max_rss`/`max_cpu` gets: a warning and its flag, or also a
    restart."""

    WARN = "warn"
    RESTART = "restart"


class Policy(enum.Enum):
    OTHER = "SCHED_OTHER"
    FIFO = "SCHED_FIFO"
    RR = "SCHED_RR"


@dataclass
class ResourceLimit:
    """One `set_resource_limits` entry; None means unlimited (RLIM_INFINITY)."""

    name: str  # lower-case RLIMIT_ suffix: core, nofile, memlock, stack, rtprio, nice, as, ...
    soft: int | None
    hard: int | None


@dataclass
class OutputLog:
    path: str
    size_limit: int = 10 << 20  # bytes per file before it is rotated
    keep_count: int = 3  # rotated files kept besides the current one


@dataclass
class Watchdog:
    """Restart the process when `topic` is published at less than `min_hz` (measured over
    a window of max(1 s, 3 / min_hz)) once it has been ready."""

    topic: str
    min_hz: float


@dataclass
class Instance:
    name: str
    manager: str  # "HOST:PORT" or ":PORT"
    location: Location
    documentation: str = ""
    webui_auth_file: str | None = None  # absolute path; LNM_WEBUI_AUTH_FILE overrides it
    webui: bool = False  # `webui: on`: serve the web UI (docs/webui.md)
    webui_port: int | None = None  # its own port; None: the manager's
    # docs/security.md: "none" | "authenticate" | "encrypt"; None: the default
    # (authenticate, since every daemon has a key)
    security: str | None = None
    # absolute path; clients hold a copy ($LN_CLIENT_KEY_FILE or ~/.config/...client.key)
    client_key_file: str | None = None
    client_uids: list[str] | None = None  # users (names or numbers) admitted locally
    client_gids: list[str] | None = None  # groups (names or numbers) admitted locally
    webui_tls_cert: str | None = None  # absolute path of a PEM certificate (chain)
    webui_tls_key: str | None = None  # absolute path of its PEM private key


# What an `access` line governs (docs/security.md): a topic's publishers and subscribers, a
# service's callers and providers, a parameter block's readers and setters.
ACCESS_VERBS = ("publish", "subscribe", "call", "provide", "set")


@dataclass(frozen=True)
class AccessRule:
    """One `access` line: allow or deny `verbs` on the topics, services or parameter blocks
    `pattern` matches (fnmatch) to the clients one of `clients` matches."""

    allow: bool
    verbs: frozenset[str]
    pattern: str
    clients: tuple[str, ...]
    location: Location

    def matches(self, verb: str, name: str, client: str) -> bool:
        return (verb in self.verbs and fnmatch.fnmatchcase(name, self.pattern)
                and any(fnmatch.fnmatchcase(client, c) for c in self.clients))


@dataclass
class Host:
    """One `hosts` line: settings of a physical host."""

    name: str
    location: Location
    interfaces: dict[str, str] = field(default_factory=dict)  # label -> IPv4/IPv6 address
    process_start_rate_limit: float | None = None  # starts per second, None: unlimited
    daemon_port: int | None = None  # None: LN_ARBITER_PORT or DEFAULT_ARBITER_PORT
    daemon_start_script: str | None = None
    data_port: int | None = None  # the daemon's forwarding data port; None: ask the daemon


@dataclass(frozen=True)
class Interface:
    """An interface of a host as given in `hosts`: its label and address."""

    host: str
    label: str
    address: str


@dataclass(frozen=True)
class Member:
    """One item of a network's `member_interfaces`: either an interface of a host
    (`HOST/IFACE`: `host` and `interface` set) or a subnet (`IP/BITS`: `subnet` set,
    normalised, e.g. "10.0.0.0/24")."""

    location: Location
    host: str | None = None
    interface: str | None = None
    subnet: str | None = None

    def __str__(self) -> str:
        return self.subnet if self.subnet is not None else f"{self.host}/{self.interface}"

    def matches(self, iface: Interface) -> bool:
        if self.subnet is None:
            return iface.host == self.host and iface.label == self.interface
        return ipaddress.ip_address(iface.address) in ipaddress.ip_network(self.subnet)


@dataclass
class Network:
    """A `network NAME` section: interfaces that reach each other directly.  Hosts with an
    interface in a common network talk directly; others need a host that forwards."""

    name: str
    location: Location  # of the section header
    members: list[Member] = field(default_factory=list)
    excluded: list[Member] = field(default_factory=list)  # `!` items
    preferred_gateways: list[str] = field(default_factory=list)  # host names
    # The resolved members: every interface in `hosts` that a member matches and no
    # exclusion does, in the order of `hosts` and of each host's interfaces.
    interfaces: list[Interface] = field(default_factory=list)

    def hosts(self) -> list[str]:
        """The hosts with an interface in this network, without repeats, in order."""
        return list(dict.fromkeys(i.host for i in self.interfaces))


DEFAULT_PULL_PORT = default_ports.PULL_PORT


@dataclass(frozen=True)
class PullSetting:
    """The `pull:...` settings of a `topics` line (docs/pull.md): how the daemons of the
    publishers' hosts serve the topics to NDN consumers."""

    transport: str  # "ndn-udp", or "off": the topics it matches are not served
    port: int = DEFAULT_PULL_PORT
    prefix: str | None = None  # NDN name prefix, "/a/b"; None: /ln/<instance name>
    history: int = 64  # samples kept per topic
    freshness_ms: int = 1000  # FreshnessPeriod of sample Data
    key: bytes = b""  # HMAC-SHA256 key; empty: DigestSha256 signatures
    address: str = "0.0.0.0"  # the daemon's bind address


@dataclass(frozen=True)
class TopicSetting:
    """One line of a `topics` section: the settings of the topics `pattern` matches (a
    topic name or an fnmatch glob, case-sensitive).  Each setting comes from the first
    matching line that has it."""

    pattern: str
    transport: str | None  # "udp" or "tcp": how samples go to other hosts; None: not set
    location: Location
    pull: PullSetting | None = None  # None: not set on this line

    def matches(self, topic: str) -> bool:
        return fnmatch.fnmatchcase(topic, self.pattern)


@dataclass(frozen=True)
class LoggerTopic:
    """One line of a `logger` section: the topics `pattern` matches (a name or an fnmatch
    glob) are logged on their publishers' hosts, `depth` samples deep, keeping every
    sample whose sequence number is a multiple of `divisor`, none older than `span`
    seconds before the newest (0: no span)."""

    pattern: str
    depth: int
    location: Location
    divisor: int = 1
    span: float = 0.0

    def matches(self, topic: str) -> bool:
        return fnmatch.fnmatchcase(topic, self.pattern)


@dataclass
class Logger:
    """A `logger NAME` section (docs/logging.md): its topics, and whether the manager
    enables it as soon as it runs."""

    name: str
    location: Location
    autostart: bool = False
    topics: list[LoggerTopic] = field(default_factory=list)  # in file order


@dataclass
class Process:
    name: str  # full name, with the push_name_prefix prefixes joined by "/"
    location: Location  # of the section header
    command: str
    node: str = "localhost"  # "localhost": the manager's host
    # The command split into words (config/argv.py), empty with start_in_shell.
    argv: list[str] = field(default_factory=list, compare=False)  # derived: not compared
    environment: dict[str, str] = field(default_factory=dict)
    pass_environment: list[str] = field(default_factory=list)  # names copied from the manager
    change_directory: str | None = None
    # Processes or states that must be ready (states: UP) before this one starts, and stay so.
    depends_on: list[str] = field(default_factory=list)
    # Processes that must have finished successfully before this one starts.
    start_before: list[str] = field(default_factory=list)
    # Processes started as soon as this one is ready.
    start_on_ready: list[str] = field(default_factory=list)
    ready_regex: str | None = None  # Python re syntax, searched in each output line
    # Python re syntax: an output line it matches is a log line, its level the group `level`
    # (debug, info, warning/warn, error, critical/fatal, ...), its text the group `text`
    log_level_regex: str | None = None
    ready_time: float | None = None  # seconds after start
    ready_on_topic: str | None = None  # ready once that topic has a publisher
    ready_on_service: str | None = None  # ready once that service is registered
    term_signal: int = int(signal.SIGTERM)
    term_timeout: float = 5.0  # seconds before SIGKILL
    policy: Policy = Policy.OTHER
    priority: int = 0  # nice value for SCHED_OTHER, 1..99 for FIFO/RR
    affinity: list[int] | None = None  # CPU numbers
    # Where each key of the section was written (its value), for checks after the load.
    key_locations: dict[str, Location] = field(default_factory=dict, compare=False,
                                               repr=False)
    resource_limits: list[ResourceLimit] = field(default_factory=list)
    output_log: OutputLog | None = None
    max_output_lines: int = 1000  # lines of output kept in memory
    output_encoding: str = "utf-8"
    flags: set[str] = field(default_factory=set)
    restart: Restart = Restart.NEVER
    restart_limit: int = 5  # restarts in a row before giving up (state failed)
    restart_delay: float = 1.0  # seconds before the first restart; doubles, at most 30 s
    watchdog: Watchdog | None = None
    max_rss: int | None = None  # bytes of resident memory before it is flagged
    max_cpu: float | None = None  # % of one core (a sample's) before it is flagged
    on_limit: OnLimit = OnLimit.WARN
    message_definition_dirs: list[str] = field(default_factory=list)
    # Initial overrides of its parameter blocks: block -> parameter -> value (plain JSON
    # values); passed as $LN_PARAMETERS (docs/parameters.md).
    parameters: dict[str, dict[str, object]] = field(default_factory=dict)

    @property
    def has_readiness(self) -> bool:
        return any(x is not None for x in (self.ready_regex, self.ready_time,
                                           self.ready_on_topic, self.ready_on_service))


@dataclass
class State:
    """A `state` section: CHECK exit 0 means UP; `up`/`down` bring it there."""

    name: str
    location: Location
    check: str
    up: str | None = None
    down: str | None = None
    node: str | None = None  # None: the node of a process that depends on it, else localhost
    min_check_interval: float = 30.0


@dataclass
class Group:
    name: str
    location: Location
    members: list[str] = field(default_factory=list)  # resolved process/state/group names
    flags: set[str] = field(default_factory=set)


@dataclass
class Config:
    files: list[str]  # every file read, the main one first
    instance: Instance
    defines: dict[str, str] = field(default_factory=dict)  # final values
    hosts: dict[str, Host] = field(default_factory=dict)
    node_map: dict[str, str] = field(default_factory=dict)  # logical node -> host
    networks: dict[str, Network] = field(default_factory=dict)  # in file order
    topic_settings: list[TopicSetting] = field(default_factory=list)  # in file order
    processes: dict[str, Process] = field(default_factory=dict)  # in file order
    states: dict[str, State] = field(default_factory=dict)
    groups: dict[str, Group] = field(default_factory=dict)
    message_definition_dirs: list[str] = field(default_factory=list)
    loggers: dict[str, Logger] = field(default_factory=dict)  # in file order
    access_rules: list[AccessRule] = field(default_factory=list)  # in file order
    # Problems that did not stop the load (config.errors.Problem; `--strict` makes them
    # errors)
    warnings: list = field(default_factory=list)


def topic_transport(config: Config, topic: str) -> str | None:
    """The transport the `topics` sections give `topic` ("udp" or "tcp"): that of the first
    line, in file order, that sets one and whose pattern matches it; None if none does."""
    for setting in config.topic_settings:
        if setting.transport is not None and setting.matches(topic):
            return setting.transport
    return None


def topic_pull(config: Config, topic: str) -> PullSetting | None:
    """How `topic` is served to pull consumers: the pull settings of the first line that
    sets `pull` and matches it; None if none does or that line says `pull:off`."""
    for setting in config.topic_settings:
        if setting.pull is not None and setting.matches(topic):
            return setting.pull if setting.pull.transport != transports.PULL_OFF else None
    return None
