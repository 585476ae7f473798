"""The keys of a `process` section: what each accepts and where it goes in the model.
Scalar keys take one value (a later line replaces it); list keys are replaced by
`KEY:` and extended by `add KEY:`."""

from __future__ import annotations

import codecs
import re
from collections.abc import Callable
from typing import TYPE_CHECKING

from .drafts import KeyLine, ProcessDraft, Ref
from .errors import LineError, Problem, closest, did_you_mean
from .model import ResourceLimit
from .process_params import parameters_key
from .text import Value, split_value
from .values import (
    env_name,
    fail,
    parse_affinity,
    parse_duration,
    parse_env_entry,
    parse_float,
    parse_int,
    parse_on_limit,
    parse_policy,
    parse_resource_limits,
    parse_restart,
    parse_signal,
    parse_size,
    parse_topic,
    parse_watchdog,
    split_env_entries,
)

if TYPE_CHECKING:
    from .parser import Parser

FLAGS = frozenset("""forward_x11 forward_x11_to_gui no_error_on_stop no_error_on_successful_stop
    dont_stop_dependent_procs no_skip_display blocking_output no_host_default_templates
    no_default_templates disable_gdb_run disable_gdb_rerun no_vte use_vte
    dont_translate_backspace_to_delete start_in_shell disable_stop remove_color_codes no_pty
    no_state_led no_warning_window no_ln_ld_library_path set_user_and_home""".split())

# Flags of the original that only change its GTK GUI or how it shows output, and flags
# that opt out of something links_and_nodes never does: accepted, no effect.
FLAGS_WITHOUT_EFFECT = frozenset("""forward_x11_to_gui no_skip_display blocking_output
    no_host_default_templates no_default_templates disable_gdb_run disable_gdb_rerun no_vte
    use_vte dont_translate_backspace_to_delete remove_color_codes no_state_led
    no_warning_window no_ln_ld_library_path""".split())

# Keys of the original that only change its GTK GUI or output buffering: read and dropped.
IGNORED = frozenset("""vte_color_style line_highlight_fg_color line_highlight_bg_color
    line_highlight_regexes bugtracker_url mantis_project_id notebook documentation
    warning_regex warning_msg max_output_frequency output_buffer_size
    max_queued_output_bytes gui""".split())

# Keys of the original that change what runs, which this manager does not implement,
# with the nearest thing that it does.
UNSUPPORTED = {
    "auto_restart_interval": "use 'restart' and 'restart_delay'",
    "derive_from": "use a template and 'use_template'",
    "depends_on_restart": "use 'depends_on': a dependent is stopped and started again "
                          "with its dependency",
    "start_tool": "put the tool in 'command'",
    "arch": "choose the host with 'node'",
    "map_service": "pass the service name to the program in 'command' or 'environment'",
    "map_topic": "pass the topic name to the program in 'command' or 'environment'",
    "change_user_to": "run the ln_daemon of that node as the user, or use sudo in "
                      "'command'",
    "provides": "use 'ready_on_topic' or 'ready_on_service'",
    "undef": "'undef' works in a defines section",
    "change_dictionary": "use 'change_directory'",
}

Scalar = Callable[[ProcessDraft, Value, "Parser", KeyLine], None]
ListKey = Callable[[ProcessDraft, list[Value], "Parser", KeyLine], None]
_GLOB = re.compile(r"[*?\[\]]")


def _word(v: Value, key: str) -> str:
    if not v.text or any(c.isspace() for c in v.text):
        raise fail(v, f"'{key}' must be one word, got '{v.text}'")
    return v.text


def _nonempty(v: Value, key: str) -> str:
    if not v.text.strip():
        raise fail(v, f"'{key}' needs a value")
    return v.text


def _command(d: ProcessDraft, v: Value, p: Parser, kl: KeyLine) -> None:
    d.process.command = _nonempty(v, "command")
    d.has_command = True
    d.command_value = v


def _regex(d: ProcessDraft, v: Value, p: Parser, kl: KeyLine) -> None:
    try:
        re.compile(v.text)
    except re.error as exc:
        raise fail(v, f"bad 'ready_regex': {exc.msg}", exc.pos or 0) from None
    d.process.ready_regex = v.text


def _log_level_regex(d: ProcessDraft, v: Value, p: Parser, kl: KeyLine) -> None:
    try:
        compiled = re.compile(v.text)
    except re.error as exc:
        raise fail(v, f"bad 'log_level_regex': {exc.msg}", exc.pos or 0) from None
    if "level" not in compiled.groupindex:
        raise fail(v, "'log_level_regex' needs a group named level, as in "
                      "'^\\[(?P<level>[A-Z]+)\\] (?P<text>.*)'")
    d.process.log_level_regex = v.text


def _encoding(d: ProcessDraft, v: Value, p: Parser, kl: KeyLine) -> None:
    try:
        d.process.output_encoding = codecs.lookup(v.text).name
    except LookupError:
        raise fail(v, f"unknown output encoding '{v.text}'") from None


def _set(attr: str, parse: Callable[[Value, str], object]) -> Scalar:
    def apply(d: ProcessDraft, v: Value, p: Parser, kl: KeyLine) -> None:
        setattr(d.process, attr, parse(v, kl.key))
    return apply


def _set_log(attr: str, parse: Callable[[Value, str], object]) -> Scalar:
    def apply(d: ProcessDraft, v: Value, p: Parser, kl: KeyLine) -> None:
        setattr(d, attr, parse(v, kl.key))
    return apply


SCALARS: dict[str, Scalar] = {
    "node": _set("node", _word),
    "command": _command,
    "change_directory": lambda d, v, p, kl: setattr(
        d.process, "change_directory", p.path(_nonempty(v, kl.key), kl)),
    "ready_regex": _regex,
    "log_level_regex": _log_level_regex,
    "ready_time": _set("ready_time", parse_duration),
    "ready_on_topic": _set("ready_on_topic", lambda v, k: parse_topic(v, "topic")),
    "ready_on_service": _set("ready_on_service", lambda v, k: parse_topic(v, "service")),
    "term_signal": _set("term_signal", parse_signal),
    "term_timeout": _set("term_timeout", parse_duration),
    "policy": _set("policy", parse_policy),
    "priority": _set("priority", parse_int),
    "affinity": _set("affinity", parse_affinity),
    "output_logfile": lambda d, v, p, kl: setattr(d, "log_path",
                                                  p.path(_nonempty(v, kl.key), kl)),
    "output_logfile_size_limit": _set_log("log_size", lambda v, k: _positive_size(v, k)),
    "output_logfile_keep_count": _set_log("log_keep", lambda v, k: parse_int(v, k, 0)),
    "max_output_lines": _set("max_output_lines", lambda v, k: parse_int(v, k, 0)),
    "output_encoding": _encoding,
    "restart": _set("restart", parse_restart),
    "restart_limit": _set("restart_limit", lambda v, k: parse_int(v, k, 0)),
    "restart_delay": _set("restart_delay", parse_duration),
    "watchdog_topic": _set("watchdog", parse_watchdog),
    "stack_size": lambda d, v, p, kl: _stack_size(d, v),
    "max_rss": _set("max_rss", lambda v, k: _positive_size(v, k)),
    "max_cpu": _set("max_cpu", lambda v, k: parse_float(v, k, 0, above=True)),
    "on_limit": _set("on_limit", parse_on_limit),
}


def _stack_size(d: ProcessDraft, v: Value) -> None:
    """`stack_size: SIZE` is the stack resource limit (soft and hard)."""
    size = _positive_size(v, "stack_size")
    kept = [x for x in d.process.resource_limits if x.name != "stack"]
    d.process.resource_limits = [*kept, ResourceLimit("stack", size, size)]


def _positive_size(v: Value, key: str) -> int:
    n = parse_size(v, key)
    if n <= 0:
        raise fail(v, f"'{key}' must be more than 0 bytes")
    return n


def _collect(values: list[Value], parse: Callable[[Value], object]) -> list:
    """parse() of every value; all problems reported together."""
    out, problems = [], []
    for v in values:
        try:
            out.append(parse(v))
        except LineError as exc:
            problems.extend(exc.problems)
    if problems:
        raise LineError(problems)
    return out


def _environment(d: ProcessDraft, values: list[Value], p: Parser, kl: KeyLine) -> None:
    entries = [e for v in values for e in split_env_entries(v)]
    pairs = _collect(entries, lambda e: parse_env_entry(e, kl.key))
    if not kl.add:
        d.process.environment.clear()
    d.process.environment.update(pairs)


def _pass_environment(d: ProcessDraft, values: list[Value], p: Parser, kl: KeyLine) -> None:
    names = _collect([i for v in values for i in split_value(v, ", \t")],
                     lambda i: env_name(i, kl.key))
    kept = d.process.pass_environment if kl.add else []
    d.process.pass_environment = list(dict.fromkeys([*kept, *names]))


def _flags(d: ProcessDraft, values: list[Value], p: Parser, kl: KeyLine) -> None:
    def check(item: Value) -> str:
        if item.text not in FLAGS:
            raise fail(item, f"unknown flag '{item.text}' in process '{d.process.name}'"
                             f"{did_you_mean(item.text, FLAGS)}")
        return item.text
    flags = _collect([i for v in values for i in split_value(v, ", \t")], check)
    if not kl.add:
        d.process.flags.clear()
    d.process.flags.update(flags)


def _limits(d: ProcessDraft, values: list[Value], p: Parser, kl: KeyLine) -> None:
    limits = [x for group in _collect(values, lambda v: parse_resource_limits(v, kl.key))
              for x in group]
    kept = d.process.resource_limits if kl.add else []
    merged = {x.name: x for x in [*kept, *limits]}
    d.process.resource_limits = list(merged.values())


def ref_items(values: list[Value], kl: KeyLine, exclusions: bool = False) -> list[Ref]:
    """The names of a reference list, checked to be usable as names."""
    def ref(item: Value) -> Ref:
        text = item.text
        exclude = exclusions and text.startswith("!")
        if exclude:
            text = text[1:].strip()
        if not text or (not exclusions and _GLOB.search(text)):
            raise fail(item, f"bad name '{item.text}' in '{kl.key}'")
        return Ref(text, item.loc, kl.scopes, kl.ctx.note, exclude)
    return _collect([i for v in values for i in split_value(v)], ref)


def _refs(d: ProcessDraft, values: list[Value], p: Parser, kl: KeyLine) -> None:
    refs = ref_items(values, kl)
    if not kl.add:
        d.refs[kl.key].clear()
    d.refs[kl.key].extend(refs)


LISTS: dict[str, ListKey] = {
    "environment": _environment,
    "pass_environment": _pass_environment,
    "depends_on": _refs,
    "start_before": _refs,
    "start_on_ready": _refs,
    "flags": _flags,
    "set_resource_limits": _limits,
    "parameters": parameters_key,  # process_params.py
}

KNOWN = frozenset(SCALARS) | frozenset(LISTS) | IGNORED


def process_key(d: ProcessDraft, kl: KeyLine, p: Parser) -> None:
    """Apply one key line to the process being read."""
    key = kl.key
    if key in IGNORED:
        return
    if key in UNSUPPORTED:
        hint = UNSUPPORTED[key]
        raise LineError.at(kl.loc, f"key '{key}' of the original Links and Nodes is not "
                                   f"supported by links_and_nodes ({hint})")
    if key in LISTS:
        LISTS[key](d, p.values(kl), p, kl)
    elif key in SCALARS:
        if kl.add:
            raise LineError.at(kl.loc, f"'add' works on list keys only; '{key}' takes one "
                                       "value")
        SCALARS[key](d, p.scalar(kl), p, kl)
    else:
        meant = closest(key, KNOWN)
        if meant:  # the key meant is not missing, it is misspelt
            d.failed.add(meant)
        hint = f" (did you mean '{meant}'?)" if meant else ""
        raise LineError([Problem(kl.loc, f"unknown key '{key}' in process "
                                         f"'{d.process.name}'{hint}")])
    d.key_locs[key] = (kl.pieces[0].loc if kl.pieces else kl.block_loc or kl.loc,
                       kl.ctx.note)
