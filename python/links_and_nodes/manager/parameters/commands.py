"""The `param ...` commands in the command table (docs/parameters.md): `param list|get|set|
reset|changes|save|load` and param_blocks, a family of phrases for the console and
`ln_manager param`, the scripting API's param_* methods and the web UI's parameter view.
They run in the client, which calls the blocks' services (tools/parameters/commands.py)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ...tools.commands import Arg, Command, Verb, register
from ...tools.parameters import commands as run

_BLOCK = Arg("block", "str", "a parameter block (its id or a unique end of it)",
             required=True, nonempty=True, positional=True)
_JSON = Arg("json", "bool", "the answer as JSON", default=False, where="text")


def _param(name: str, help_text: str, args: tuple[Arg, ...], result: str, **more: Any) -> Command:
    return Command(name, help_text, "parameters", None, args, result=result,
                   run=getattr(run, name), phrase=name.replace("_", " "), **more)


def _set_args(block: str, name: str | dict[str, Any], value: Any = None) -> dict[str, Any]:
    return {"block": block, "values": name if isinstance(name, dict) else {name: value}}


def _reset_args(block: str, name: str | list[str] | None = None) -> dict[str, Any]:
    return {"block": block, "names": name}


def _path_args(path: str | Path) -> dict[str, Any]:
    return {"path": str(path)}


_LISTING = "{id, block, client, service, generation, updates, config_errors, parameters}"

register(
    Command("param_blocks", "the parameter blocks", "parameters", None, (),
            result="blocks: [{id, service, provider}]", run=run.param_blocks,
            console=False, cli=False,
            script_result=lambda answer: [b["id"] for b in answer["blocks"]],
            script_doc='The ids ("<client>.<block>") of every parameter block.'),
    _param("param_list", "the blocks, or the parameters of one block",
           (Arg("block", "str", "a parameter block (none: every block)", default="",
                positional=True), _JSON),
           f"{_LISTING} of a block (values as of the loop's last copy), or blocks: [{{block, "
           "service, client, parameters, overridden, updates}]",
           console_format=run.list_lines,
           script_doc="The block's descriptors as its service lists them (values as of the "
                      "loop's last copy); without a block, every block with its number of "
                      "parameters, of overrides and of updates."),
    _param("param_get", "values as the loop has them now",
           (_BLOCK, Arg("name", "str", "one parameter (none: all)", positional=True,
                         metavar="PARAM", nullable=True),
            Arg("wait", "float", "seconds to wait for the loop's update (default 0.25)",
                low=0, high=10, metavar="S", nullable=True,
                error="--wait needs a number of seconds 0..10"), _JSON),
           f"{_LISTING} with the loop's values now, live, values_update",
           console_format=run.get_lines, script_result=run.values_of, missing_usage=True,
           script_doc="The value of parameter `name` as the loop has it now (its next "
                      "update(), at most `wait` s, default 0.25), or {name: value} of every "
                      "parameter of the block."),
    _param("param_set", "override (several: all at once or none)",
           (_BLOCK, Arg("values", "json", "PARAM VALUE pairs; in JSON {parameter: value}",
                        required=True, positional=True, rest="words", check=run.pairs,
                        metavar="PARAM VALUE [PARAM VALUE ...]"), _JSON),
           "id, generation, set: [names]", changes_state=True, console_format=run.set_lines,
           missing_usage=True, script_args=_set_args,
           script_result=lambda answer: int(answer["generation"]),
           script_doc="Override parameter `name` with `value`, or several at once with a "
                      "dict {name: value} (all or none); visible at the loop's next "
                      "update().  Returns the block's generation of the change."),
    _param("param_reset", "back to the program's own value",
           (_BLOCK, Arg("names", "json", "the parameters (none: every override)",
                        positional=True, rest="words", check=run.names, metavar="PARAM ..."),
            _JSON),
           "id, generation, reset: [names that had an override]", changes_state=True,
           console_format=run.reset_lines, missing_usage=True, script_args=_reset_args,
           script_result=lambda answer: answer["reset"],
           script_doc="Remove the override of `name` (a list of them, or every one); returns "
                      "the parameters that had one."),
    _param("param_changes", "the block's last changes (--follow: and new ones as they come)",
           (_BLOCK, Arg("since", "int", "after this generation", default=0, low=0,
                        metavar="G"),
            Arg("follow", "bool", "go on with new ones until stopped", default=False,
                where="text"), _JSON),
           "rows: [{generation, time, op, parameters, values}]", streams=True,
           console_format=run.change_lines, missing_usage=True,
           script_result=lambda rows: [r for r in rows if "note" not in r],
           script_doc="The block's remembered changes (its last 64) after generation "
                      "`since`, oldest first: {\"generation\", \"time\" (s, CLOCK_REALTIME), "
                      "\"op\" (\"set\", \"config\", \"reset\"), \"parameters\", \"values\" (a "
                      "set's values, if small)}."),
    _param("param_save", "every block's settings to a JSON file",
           (Arg("path", "str", "the file", required=True, nonempty=True, positional=True,
                metavar="FILE"), _JSON),
           "path, blocks, parameters", changes_state=True, console_format=run.save_lines,
           missing_usage=True, script_args=_path_args,
           script_doc="Write every block's writable values to a JSON file here; {\"path\", "
                      "\"blocks\", \"parameters\"}."),
    _param("param_load", "set the values of a file param save wrote",
           (Arg("path", "str", "the file", required=True, nonempty=True, positional=True,
                metavar="FILE"), _JSON),
           "path, loaded: [ids], errors: [texts]", changes_state=True,
           console_format=run.load_lines, failed=run.load_failed, missing_usage=True,
           script_args=_path_args,
           script_doc="Set the values of a file written by param_save, one request per "
                      "block; {\"path\", \"loaded\": [ids], \"errors\": [texts]} (blocks "
                      "missing or refusing are only listed)."),
    Verb("param", "parameter blocks of the processes (docs/parameters.md)", "parameters",
         choose="command"),
)
