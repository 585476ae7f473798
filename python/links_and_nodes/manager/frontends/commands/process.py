"""The table entries of the process and system commands: start, stop, restart, wait_ready,
status, output, history, topics, services, hosts, network, reload, quit, detach.  Their
handlers are Control's methods (control.py); their text is in views.py."""

from __future__ import annotations

from typing import Any

from ....tools.commands.spec import Arg, Command
from ....tools.commands.table import register
from . import views

MAX_OUTPUT_LINES = 10000


def _target(help_text: str, console_required: bool = True) -> Arg:
    return Arg("target", "str", help_text, default="all", positional=True, nonempty=True,
               console_required=console_required, metavar="NAME|GROUP|all",
               error='"target" must be a process, a group or "all"')


_NAME = Arg("name", "str", "a process", required=True, positional=True, nonempty=True)
_PROCESSES = "processes: the names of the processes it concerned"


def _method(name: str) -> Any:
    async def handler(control: Any, args: dict[str, Any]) -> dict[str, Any]:
        return dict(await getattr(control, name)(args))
    handler.__name__ = name
    return handler


async def _console_output(console: Any, args: dict[str, Any]) -> None:
    """`output NAME [-n N] [-f]`: the last lines, then (-f) every new one until the next
    command line."""
    result = await console.control.handle({"op": "output", "name": args["name"],
                                           "n": args["n"]})
    for text in views.format_output(result, args):
        console.say(text)
    if args["follow"]:
        console.follow_output(args["name"])


async def _console_end(console: Any, args: dict[str, Any], op: str) -> bool:
    await console.control.handle({"op": op})
    return True


def _cli_start(mgr: Any, args: dict[str, Any]) -> list[str]:
    names = mgr.start(args["target"])
    if args["wait"]:
        mgr.wait_ready(args["target"], args["timeout"])
    return [f"{'ready' if args['wait'] else 'starting'}: {', '.join(names)}"]


_SECONDS = '"timeout" must be a number of seconds >= 0 or null'

register(
    Command(
        "status", "every process: state, pid, node, why", "processes", _method("status"),
        result="processes: [{name, state, pid, node, reason, exit_code, restarts, ...}], "
               "states: [{name, up}]",
        console_format=views.format_status,
        cli_help="every process with state, pid, node and reason",
        json_view=lambda result: result["processes"],
        script_result=lambda result: result["processes"],
        script_doc="One dict per process: name, state, pid, node, reason, exit_code, "
                   "restarts, ..."),
    Command(
        "start", "start (dependencies first)", "processes", _method("start"),
        (_target("a process, a group or all"),
         Arg("wait", "bool", "return once they are ready", where="cli"),
         Arg("timeout", "float", "for --wait, in seconds", nullable=True, low=0,
             where="cli", error=_SECONDS, metavar="S")),
        result=_PROCESSES, changes_state=True,
        console_format=views.format_processes("starting"),
        cli_help="start a process, group or all (dependencies first)", cli_run=_cli_start,
        script_result=lambda result: result["processes"],
        script_doc='Start a process, a group or "all" (with dependencies); returns at '
                   'once.'),
    Command(
        "stop", "stop (dependents first)", "processes", _method("stop"),
        (_target("a process, a group or all"),
         Arg("force", "bool", "also processes with disable_stop", default=False)),
        result=_PROCESSES, changes_state=True, slow=True,
        console_format=views.format_processes("stopped"),
        cli_help="stop a process, group or all (dependents first)",
        script_result=lambda result: result["processes"],
        script_doc="Stop (dependents first); returns once they are down."),
    Command(
        "restart", "stop, then start", "processes", _method("restart"),
        (_target("a process, a group or all"),),
        result=_PROCESSES, changes_state=True, slow=True,
        console_format=views.format_processes("restarted"),
        script_result=lambda result: result["processes"]),
    Command(
        "wait_ready", "wait until a process, group or all is ready", "processes",
        _method("wait_ready"),
        (_target("a process, a group or all", console_required=False),
         Arg("timeout", "float", "seconds (none: forever)", nullable=True, low=0,
             error=_SECONDS, metavar="S")),
        result="{} once every one is ready (or finished)", slow=True, console=False,
        cli_format=lambda result, args: ["ready"], script_result=lambda result: None,
        script_wait="timeout",
        script_doc="Until everything of `target` is ready (or finished); ManagerError as "
                   "soon as one of them fails, or after `timeout` seconds."),
    Command(
        "output", "last N lines (default 20); -f follows until the next command",
        "processes", _method("output"),
        (_NAME,
         Arg("n", "int", "lines", default=100, text_default=20, flag="-n", low=0,
             high=MAX_OUTPUT_LINES, error=f'"n" must be 0..{MAX_OUTPUT_LINES}'),
         Arg("follow", "bool", "follow until the next command", flag="-f", where="console",
             default=False)),
        result="lines: [{time, stream, text}]", console_run=_console_output,
        cli_help="recent output of a process", cli_format=views.format_output_plain,
        script_result=lambda result: [line["text"] for line in result["lines"]],
        script_doc="The last `n` lines of a process's output."),
    Command(
        "history", "every state transition of a process", "processes", _method("history"),
        (_NAME,), result="transitions: [{time, state, reason}]",
        console_format=views.format_history,
        script_result=lambda result: result["transitions"],
        script_doc="Every state transition of a process: time, state, reason."),
    Command(
        "topics", "topics with publishers, subscribers and samples", "topics",
        _method("topics"),
        result="topics: [{name, md_name, publishers, subscribers, published}]",
        console_format=views.format_topics, script_result=lambda result: result["topics"]),
    Command(
        "services", "services with provider, md and calls", "services", _method("services"),
        result="services: [{name, provider, md_name, calls, errors, ...}]",
        console_format=views.format_services,
        script_result=lambda result: result["services"]),
    Command(
        "hosts", "every host: its ln_daemon's state, host id, data port", "hosts",
        _method("hosts"),
        result="hosts: [{name, state, error, host_id, data_port, local, for_s, ...}]",
        console_format=views.format_hosts, script_result=lambda result: result["hosts"],
        script_doc="One dict per configured host: name, state (connecting/up/unreachable), "
                   "error, host_id, data_port, local, for_s (seconds in that state), "
                   "unknown_stream, malformed (datagrams its daemon could not place)."),
    Command(
        "network", "topics forwarded between hosts: rates, drops, per host pair; pull "
                   "producers' counters per host (docs/pull.md)", "hosts",
        _method("network"),
        result="streams: [{topic, src, dst, transport, msgs_per_s, bytes_per_s, drops, "
               "...}], pairs: [{src, dst, topics, msgs_per_s, bytes_per_s, drops}], "
               "problems: [{topic, src, dst, error}], pull: [per host]",
        console_format=views.format_network,
        cli_help="topics forwarded between hosts and the pull producers' counters",
        script_result=lambda result: result,
        script_doc='Forwarding between hosts: {"streams": [per topic and hop: topic, src, '
                   'dst, transport, active, connected, sent, received, msgs_per_s, '
                   'bytes_per_s, drops, send_drops, recv_drops, stale, invalid, rejected, '
                   'error], '
                   '"pairs": [per host pair: src, dst, topics, msgs_per_s, bytes_per_s, '
                   'drops], "problems": [topic, src, dst, error], "pull": [per host]}.'),
    Command(
        "reload", "read the configuration file again", "manager", _method("reload"),
        result="per kind of change (added, removed, changed, ...): the names",
        changes_state=True, console_format=views.format_reload,
        script_result=lambda result: result),
    Command(
        "quit", "stop every process and exit", "manager", _method("quit"),
        changes_state=True, aliases=("exit",),
        console_run=lambda console, args: _console_end(console, args, "quit"),
        cli_help="stop every process and end the manager", cli_format=views.nothing,
        script_result=lambda result: None,
        script_doc="Stop every process and end the manager."),
    Command(
        "detach", "exit, leaving the processes running under their daemons", "manager",
        _method("detach"), changes_state=True,
        console_run=lambda console, args: _console_end(console, args, "detach"),
        cli_help="end the manager, leaving the processes running", cli_format=views.nothing,
        script_result=lambda result: None,
        script_doc="End the manager; its processes keep running under their daemons."),
)
