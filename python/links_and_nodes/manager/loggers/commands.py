"""The commands of topic loggers (docs/logging.md, "Control commands"): their table entries
and handlers around loggers.Loggers.  They are a family of phrases (commands/phrases.py):
`logger NAME add TOPIC` in the console and in `ln_manager`; their text views are in
logger_cli.py.  `logger_fetch` carries samples as base64 of packed (u64 seq, i64 publish
time ns, message bytes) records, at most FETCH_MAX bytes of them per answer, so an answer
stays within the protocol's 1 MiB frame.  Light to import: loggers.py (libln) and
logger_files.py (numpy) are loaded when a command runs."""

from __future__ import annotations

import base64
from pathlib import Path
from typing import Any

from ...tools.commands import Arg, ArgError, Command, Verb, register, to_request

FETCH_MAX = 512 * 1024  # logger_files.FETCH_MAX (checked in tests/python/loggers)


def _name(value: str) -> str:
    from .loggers import LoggerError, check_name

    try:
        return check_name(value)
    except LoggerError as exc:
        raise ArgError(str(exc), "EINVAL") from None


def _depth(value: int) -> int:
    from .loggers import MAX_DEPTH

    if value > MAX_DEPTH:
        raise ArgError(f'"depth" must be an integer from 1 to {MAX_DEPTH}', "EINVAL")
    return value


def _pattern(value: str) -> str:
    from ..registry.model import topic_name_problem

    if not any(c in value for c in "*?[") and (problem := topic_name_problem(value)):
        raise ArgError(problem, "EINVAL")
    return value


# ---- handlers ------------------------------------------------------------------------------
async def logger_open(control: Any, c: dict[str, Any]) -> dict[str, Any]:
    return {"name": control._loggers().open(c["name"]).name}


async def logger_add(control: Any, c: dict[str, Any]) -> dict[str, Any]:
    from .loggers import check_pattern

    spec = check_pattern(c["topic"], c["depth"], c["divisor"], c["span"])
    await control._loggers().add(c["name"], spec)
    return dict(await control._loggers().status(c["name"]))


async def logger_remove(control: Any, c: dict[str, Any]) -> dict[str, Any]:
    await control._loggers().remove(c["name"], c["topic"])
    return {}


async def logger_enable(control: Any, c: dict[str, Any]) -> dict[str, Any]:
    await control._loggers().enable(c["name"], c["keep"])
    return {}


async def logger_disable(control: Any, c: dict[str, Any]) -> dict[str, Any]:
    await control._loggers().disable(c["name"])
    return {}


async def logger_status(control: Any, c: dict[str, Any]) -> dict[str, Any]:
    return dict(await control._loggers().status(c["name"]))


async def logger_list(control: Any, c: dict[str, Any]) -> dict[str, Any]:
    return {"loggers": control._loggers().listing()}


async def logger_fetch(control: Any, c: dict[str, Any]) -> dict[str, Any]:
    from ...logger_files import pack_samples

    chunk = await control._loggers().fetch(c["name"], c["topic"], c["host"], c["after"],
                                           c["max_bytes"])
    return {"md_name": chunk.md_name, "layout_hash": f"{chunk.layout_hash:016x}",
            "message_size": chunk.message_size, "enabled": chunk.enabled,
            "received": chunk.received, "stored": chunk.stored, "missed": chunk.missed,
            "skipped": chunk.skipped, "dropped": chunk.dropped,
            "first_seq": chunk.first_seq, "last_seq": chunk.last_seq,
            "start_seq": chunk.start_seq,
            "count": len(chunk.samples),
            "samples": base64.b64encode(pack_samples(chunk.samples)).decode()}


async def logger_save(control: Any, c: dict[str, Any]) -> dict[str, Any]:
    from .loggers import LoggerError

    path = Path(c["path"])
    if not path.is_absolute():
        raise LoggerError(f"save needs an absolute path on the manager's host, got "
                          f"{str(path)!r}", "EINVAL")
    return dict(await control._save_logger(c["name"], path, c["encoding"]))


# ---- the console's and the CLI's views --------------------------------------------------------
def _lines(op: str) -> Any:
    def view(result: dict[str, Any], args: dict[str, Any]) -> list[str]:
        from . import views as logger_cli

        return logger_cli.format_result(op, args, result)
    return view


async def _console_save(console: Any, args: dict[str, Any]) -> None:
    """`logger NAME save FILE`: a file name as typed is relative to the manager's
    directory."""
    import os

    args = {**args, "path": os.path.abspath(args["path"])}
    result = await console.control.handle(to_request(_SAVE, args))
    for text in _lines("logger_save")(result, args):
        console.say(text)


def _cli_save(mgr: Any, args: dict[str, Any]) -> list[str]:
    """`ln_manager logger NAME save FILE`: downloaded and written here, where the user is
    (--on-manager: by the manager, on its host; a relative FILE from this directory)."""
    import json

    from ... import logger_files
    from ...tools.commands import ManagerError

    path = Path(args["path"])
    if args["on_manager"]:
        result = mgr.command("logger_save", name=args["name"], path=str(path.absolute()),
                             encoding=args["encoding"])
    else:
        data = logger_files.download(lambda o, **a: mgr.command(o, name=args["name"], **a))
        try:
            result = logger_files.save(data, path, args["encoding"])
        except (OSError, ValueError) as exc:
            raise ManagerError(f"cannot save {args['path']}: {exc}") from None
    if args.get("json"):
        return json.dumps(result, indent=2).splitlines()
    return _lines("logger_save")(result, args)


# ---- the table -----------------------------------------------------------------------------
_NAME = Arg("name", "str", "the logger", required=True, check=_name, positional=True)
_STATUS = ("name, enabled, patterns: [{pattern, depth, divisor, span}], topics: [{topic, "
           "host, stored, received, missed, skipped, dropped, error}]")
_TOPIC = Arg("topic", "str", "a topic name or pattern (* ? [])", required=True, nonempty=True,
             error="a logged topic needs a name or pattern", check=_pattern, positional=True)


def _logger(name: str, help_text: str, handler: Any, *args: Arg, result: str = "{}",
            changes: bool = True, phrase: str = "", **more: Any) -> Command:
    """A logger command; with a phrase also the console's and CLI's `logger ...` words, the
    answer as logger_cli's text (--json: the answer as it came)."""
    if not phrase:
        return Command(name, help_text, "loggers", handler, args, result=result,
                       changes_state=changes, code="EINVAL", console=False, cli=False)
    return Command(name, help_text, "loggers", handler, args, result=result,
                   changes_state=changes, code="EINVAL", phrase=phrase,
                   console_format=_lines(name), json_view=lambda r: r, **more)


_SAVE = _logger(
    "logger_save", "write what a logger holds to a file on the manager's host", logger_save,
    _NAME, Arg("path", "str", "an absolute path, .mcap or .npz", required=True, nonempty=True,
               positional=True, metavar="FILE"),
    Arg("encoding", "str", "of an .mcap: ros2 (CDR, the default, what viewers decode), json "
        "or ln (raw bytes); a topic whose md is not here or that the encoding refuses stays "
        "ln", default=None, nullable=True, choices=("ros2", "json", "ln")),
    Arg("on_manager", "bool", "write the file on the manager's host instead of here",
        where="cli"),
    result="path, topics: {TOPIC: {samples, md_name, missed, dropped, gaps, encoding}}",
    phrase="logger NAME save", console_run=_console_save, cli_run=_cli_save)


register(
    _logger("logger_open", "make logger NAME if missing", logger_open, _NAME,
            result="name"),
    _logger("logger_add", "log the topics of a name or pattern", logger_add, _NAME, _TOPIC,
            Arg("depth", "int", "samples kept per topic", default=1000, low=1,
                check=_depth, positional=True),
            Arg("divisor", "int", "keep every K-th sample", default=1, low=1, metavar="K"),
            Arg("span", "float", "keep the last S seconds (0: by depth only)", default=0.0,
                low=0, high=1e9, finite=True,
                error='"span" must be a finite number of seconds >= 0', metavar="S"),
            result=_STATUS, phrase="logger NAME add"),
    _logger("logger_remove", "remove a topic pattern, or the whole logger", logger_remove,
            _NAME, Arg("topic", "str", "the pattern (none: the whole logger)", default="",
                       positional=True),
            phrase="logger NAME remove"),
    _logger("logger_enable", "start logging", logger_enable, _NAME,
            Arg("keep", "bool", "keep what was logged before", default=False),
            phrase="logger NAME enable"),
    _logger("logger_disable", "stop logging (what was logged stays)", logger_disable,
            _NAME, phrase="logger NAME disable"),
    _logger("logger_status", "a logger's patterns and topics with their counters",
            logger_status, _NAME, result=_STATUS, changes=False, phrase="logger NAME status"),
    _logger("logger_list", "every logger", logger_list,
            result="loggers: [{name, enabled, patterns, topics}]", changes=False,
            phrase="logger"),
    _logger("logger_fetch", "logged samples of one topic on one host", logger_fetch, _NAME,
            Arg("topic", "str", "the topic", required=True, nonempty=True),
            Arg("host", "str", "the host", required=True, nonempty=True),
            Arg("after", "int", "samples after this seq", default=0, low=0,
                high=(1 << 64) - 1),
            Arg("max_bytes", "int", "at most this many sample bytes", default=FETCH_MAX,
                low=1, high=FETCH_MAX),
            result="md_name, layout_hash, message_size, enabled, received, stored, missed, "
                   "skipped, dropped, first_seq, last_seq, start_seq, count, samples "
                   "(base64)", changes=False),
    _SAVE,
    Verb("logger", "topic loggers (docs/logging.md)", "loggers"),
)
