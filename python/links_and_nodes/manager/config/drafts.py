"""What the reader collects before the final checks: the model objects being filled, plus
the names they refer to (with the name prefixes in effect there) and where keys were
written, so that resolve.py can check references and report at the right place."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

from .model import (
    AccessRule,
    Group,
    Host,
    Location,
    Logger,
    Member,
    Network,
    Process,
    State,
    TopicSetting,
)
from .text import Piece, Value


@dataclass(frozen=True)
class Ctx:
    """Where a line is being read: its file, the template replay it belongs to (if any),
    and the text appended to its problems to say which template use it came from."""

    file: str
    args: Mapping[str, str] | None = None
    uses: tuple[str, ...] = ()  # "template 'T' used at FILE:LINE:COL", innermost first
    chain: tuple[str, ...] = ()  # names of the templates being replayed, outermost first

    @property
    def note(self) -> str:
        return f" (from {', from '.join(self.uses)})" if self.uses else ""


@dataclass(frozen=True)
class KeyLine:
    """A `[add] KEY: VALUE` line; `pieces` is one piece, or one per line of a `[` block."""

    key: str
    loc: Location  # of the key
    add: bool
    pieces: tuple[Piece, ...]
    block_loc: Location | None
    ctx: Ctx
    scopes: tuple[str, ...]  # name prefixes in effect, innermost first, ending with ""


@dataclass(frozen=True)
class Ref:
    """A name written in depends_on, start_before, start_on_ready or members."""

    text: str
    loc: Location
    scopes: tuple[str, ...]
    note: str = ""
    exclude: bool = False  # `!pattern` in members


@dataclass
class ProcessDraft:
    process: Process
    name_loc: Location
    refs: dict[str, list[Ref]] = field(default_factory=lambda: {
        "depends_on": [], "start_before": [], "start_on_ready": []})
    key_locs: dict[str, tuple[Location, str]] = field(default_factory=dict)  # (loc, note)
    failed: set[str] = field(default_factory=set)  # keys whose line had a problem
    has_command: bool = False
    command_value: Value | None = None  # where `command` was written, for split problems
    log_path: str | None = None
    log_size: int | None = None
    log_keep: int | None = None


@dataclass
class StateDraft:
    state: State
    name_loc: Location
    failed: set[str] = field(default_factory=set)
    has_check: bool = False


@dataclass
class GroupDraft:
    group: Group
    name_loc: Location
    members: list[Ref] = field(default_factory=list)
    failed: set[str] = field(default_factory=set)


@dataclass(frozen=True)
class HostRef:
    """A host name written in a network's `preferred_gateways`."""

    name: str
    loc: Location
    note: str = ""


@dataclass(frozen=True)
class MemberRef:
    """An item of `member_interfaces` as read; `HOST/IFACE` items are checked against
    `hosts` once all files are read."""

    member: Member
    exclude: bool
    detail_loc: Location  # of the interface label (HOST/IFACE), else of the item
    note: str = ""


@dataclass
class NetworkDraft:
    network: Network
    name_loc: Location
    items: list[MemberRef] = field(default_factory=list)
    items_loc: Location | None = None  # of the last line that set member_interfaces
    items_note: str = ""
    gateways: list[HostRef] = field(default_factory=list)
    failed: set[str] = field(default_factory=set)


@dataclass
class InstanceDraft:
    loc: Location
    name: str | None = None
    manager: str | None = None
    documentation: str = ""
    webui_auth_file: str | None = None
    webui: bool = False
    webui_port: int | None = None
    security: str | None = None
    client_key_file: str | None = None
    client_uids: list[str] | None = None
    client_gids: list[str] | None = None
    webui_tls_cert: str | None = None
    webui_tls_key: str | None = None
    failed: set[str] = field(default_factory=set)


@dataclass
class Drafts:
    """Everything read from the files, in reading order."""

    files: list[str] = field(default_factory=list)
    root: str = ""  # directory of the main file, for file names in messages
    instance: InstanceDraft | None = None
    hosts: dict[str, Host] = field(default_factory=dict)
    node_map: dict[str, str] = field(default_factory=dict)
    networks: dict[str, NetworkDraft] = field(default_factory=dict)
    topic_settings: list[TopicSetting] = field(default_factory=list)
    processes: dict[str, ProcessDraft] = field(default_factory=dict)
    states: dict[str, StateDraft] = field(default_factory=dict)
    groups: dict[str, GroupDraft] = field(default_factory=dict)
    message_definition_dirs: list[str] = field(default_factory=list)
    loggers: dict[str, Logger] = field(default_factory=dict)
    access_rules: list[AccessRule] = field(default_factory=list)  # `access` lines, in order
    order: list[str] = field(default_factory=list)  # process and state names, as defined
