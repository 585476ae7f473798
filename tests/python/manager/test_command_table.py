"""The command table (manager/frontends/commands/) and the front ends derived from it: every command
answers the same through a JSON request over the manager's CONTROL connection, the web UI's
WebSocket, the scripting API, the console on the manager's stdin and `ln_manager COMMAND`;
a bad argument is refused with the same text by each of them; every entry has help and typed arguments and shows up in
the console's help, `ln_manager --help` and the scripting API."""

from __future__ import annotations

import contextlib
import importlib.util
import json
import os
import queue
import re
import signal
import subprocess
import sys
import threading
import urllib.request
import uuid
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from buildtree import missing_test_tool
from process_management import conftest as pm

from links_and_nodes.manager.frontends import remote_cli
from links_and_nodes.manager.frontends.commands import phrases
from links_and_nodes.manager.frontends.commands.help import complete, help_command, help_text
from links_and_nodes.manager.frontends.commands.views import json_lines
from links_and_nodes.tools import commands as table
from links_and_nodes.tools.commands import ArgError, check_args, parse_words, to_request
from links_and_nodes.tools.commands.arguments import error_text
from links_and_nodes.tools.commands.spec import TYPES
from links_and_nodes.tools.scripting import Manager, ManagerError

CHILD = Path(pm.__file__).with_name("child.py")
LIMIT = pm.LIMIT
WEBSOCKETS = importlib.util.find_spec("websockets") is not None  # the WebSocket leg's client


def test_the_websocket_leg_runs() -> None:
    """The legs below compare the web UI's WebSocket only where its test client is."""
    if not WEBSOCKETS:
        missing_test_tool("the Python package websockets (requirements-dev.txt)")


# ---- the table itself (no manager) ----------------------------------------------------------
def test_every_entry_has_help_typed_args_and_every_front_end() -> None:
    cli_help = remote_cli.build_parser().format_help()
    console_help = help_text()
    names = [cmd.name for cmd in table.commands()]
    assert len(names) == len(set(names))
    for cmd in table.commands():
        assert cmd.help and cmd.group and cmd.result, cmd.name
        for arg in cmd.args:
            assert arg.help and arg.type in TYPES, (cmd.name, arg.name)
        if cmd.console_word:
            assert f"  {cmd.console_word}" in console_help, cmd.name
            assert help_command(cmd.console_word).startswith("usage: " + cmd.console_word)
        if cmd.cli_word:
            assert (cmd.family or cmd.cli_word) in cli_help, cmd.name
        if cmd.script_name:
            method = getattr(Manager, cmd.script_name)
            assert method.__doc__, cmd.name
    for cmd in table.commands()[:14]:  # the process commands: in each front end
        assert cmd.group in ("processes", "topics", "services", "hosts", "manager")
        assert cmd.script_name and (cmd.console_word or cmd.name == "wait_ready")
        assert cmd.cli_word, cmd.name
    for verb in table.verbs():  # the first word of a family of phrases
        assert verb.help and verb.name in cli_help
        assert [c for c in table.commands() if c.family == verb.name], verb.name
        assert help_command(verb.name).startswith(f"usage: {verb.name} ")


def test_a_family_of_phrases_is_table_commands(capsys: pytest.CaptureFixture[str]) -> None:
    """`logger NAME add TOPIC`: each command of the family is an entry of the table whose
    words the console and `ln_manager logger` take from it."""
    family = phrases.family("logger")
    assert {c.name for c in family} == {"logger_add", "logger_remove", "logger_enable",
                                        "logger_disable", "logger_status", "logger_list",
                                        "logger_save"}
    assert remote_cli.main(["logger", "--help"]) == 0
    cli_help = capsys.readouterr().out
    for cmd in family:
        assert cmd.script_name == cmd.name and getattr(Manager, cmd.name).__doc__
        assert cmd.usage("cli") in cli_help
        assert help_command(cmd.phrase.replace(" NAME", "")).startswith(
            "usage: " + cmd.usage("console"))
    assert "--on-manager" in cli_help and "--on-manager" not in help_text()
    cmd, words = phrases.match(["logger", "arm", "add", "a.*", "50", "--span", "2"])
    assert (cmd.name, to_request(cmd, parse_words(cmd, words))) == (
        "logger_add", {"op": "logger_add", "name": "arm", "topic": "a.*", "depth": 50,
                       "divisor": 1, "span": 2.0})
    cmd, words = phrases.match(["logger"])
    assert cmd.name == "logger_list" and words == []
    for bad in (["logger", "arm"], ["logger", "arm", "frobnicate"]):
        with pytest.raises(ArgError, match="^usage: logger NAME add TOPIC"):
            phrases.match(bad)
    assert complete("logger arm e") == ["enable"]


def test_describe_is_json_and_lists_every_command() -> None:
    described = json.loads(json.dumps(table.describe()))
    assert [d["name"] for d in described] == [c.name for c in table.commands()]
    by_name = {d["name"]: d for d in described}
    assert by_name["stop"]["changes_state"] is True
    assert by_name["status"]["changes_state"] is False
    assert by_name["output"]["args"] == [
        {"name": "name", "type": "str", "required": True, "default": None,
         "help": "a process"},
        {"name": "n", "type": "int", "required": False, "default": 100, "help": "lines",
         "low": 0, "high": 10000}]  # `-f` is the console's own: not described


def _bad_json(arg: Any) -> Any:
    return {"str": 5, "int": "x", "float": "x", "bool": "x", "json": None}[arg.type]


def _cases() -> Iterator[Any]:
    for cmd in table.commands():
        for arg in cmd.args:
            if not arg.where and arg.type != "json":
                yield pytest.param(cmd.name, arg.name, id=f"{cmd.name}-{arg.name}")


@pytest.mark.parametrize(("op", "name"), list(_cases()))
def test_a_bad_value_has_one_text_in_json_and_words(op: str, name: str) -> None:
    """A JSON request with a value of the wrong type and a console/CLI word that does not
    convert are refused with the same text (the scripting API sends JSON); an entry's own
    text may show the value as given (`-n: '0' is not ...`), then only that differs."""
    cmd = table.command(op)
    assert cmd is not None
    arg = cmd.arg(name)
    good = {a.name: {"str": "a0", "int": 1, "float": 1.0, "bool": False, "json": 1}[a.type]
            for a in cmd.args if a.required}
    with pytest.raises(ArgError) as from_json:
        check_args(cmd, {"op": op, **good, name: _bad_json(arg)})
    assert str(from_json.value) == error_text(arg, _bad_json(arg))
    if arg.type in ("bool", "str"):
        return  # a bool is a flag of no word in the console and the CLI; a word is a str
    words = [str(good[a.name]) for a in cmd.args
             if a.positional and a.required and a.name != name]
    for a in cmd.args:
        if not a.positional and a.required and a.name != name:
            words += [a.option, str(good[a.name])]
    if arg.positional:
        words.insert([a.name for a in cmd.args if a.positional].index(name), "?x")
    else:
        words += [arg.option, "?x"]
    with pytest.raises(ArgError) as from_words:
        parse_words(cmd, words)
    assert str(from_words.value) == error_text(arg, "?x")
    if "{value" not in arg.error:
        assert str(from_words.value) == str(from_json.value)


async def test_a_new_command_is_one_entry_and_its_handler(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """docs/process_management.md, "Adding a command": one register() call gives the JSON
    op, describe(), the console (with help), `ln_manager` and a scripting method."""
    import io
    from types import SimpleNamespace

    from links_and_nodes.manager.frontends.console import Console
    from links_and_nodes.manager.frontends.control import Control
    from links_and_nodes.tools.commands import Arg, Command, register
    from links_and_nodes.tools.commands import table as registry

    async def handler(control: Any, args: dict[str, Any]) -> dict[str, Any]:
        return {"said": args["text"] * args["times"]}

    entry = Command("say_demo", "say a text", "demo", handler,
                    (Arg("text", "str", "what to say", required=True, positional=True),
                     Arg("times", "int", "how often", default=1, low=1, high=3, flag="-t")),
                    result="said",
                    console_format=lambda result, args: [result["said"]])
    monkeypatch.setattr(registry, "_commands", dict(registry._commands))
    register(entry)
    control = Control(SimpleNamespace(), None)  # type: ignore[arg-type]
    assert await control.handle({"op": "say_demo", "text": "ab", "times": 2}) == \
        {"ok": True, "said": "abab"}
    assert "say_demo" in [d["name"] for d in control.describe()]
    out = io.StringIO()
    console = Console(control, out)
    await console.execute("say_demo ab -t 3")
    await console.execute("say_demo ab -t 4")
    await console.execute("help")
    assert out.getvalue().splitlines()[:2] == ["ababab", 'error: "times" must be an '
                                               "integer from 1 to 3"]
    assert "say_demo TEXT [-t T] say a text".split() in \
        [line.split() for line in out.getvalue().splitlines()]
    assert "say-demo" in remote_cli.build_parser().format_help()
    mgr = Manager.__new__(Manager)
    mgr.command = lambda op, wait=None, **args: {"ok": True, "said": f"{op}{args}"}  # type: ignore[method-assign]
    assert mgr.say_demo("x", 2) == {"said": "say_demo{'text': 'x', 'times': 2}"}


async def test_a_command_that_runs_in_the_client_streams_its_rows(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """Command.run: the command runs where its user is, yielding rows as they come; the
    console prints them (in the background), a JSON request gets {"rows": [...]}, the
    scripting method the list (with script_args's Python spelling); a rest argument takes
    the words left, the family's Verb words a line that names none of its commands, an
    Arg.error shows the value as typed."""
    import asyncio
    import io
    from types import SimpleNamespace

    from links_and_nodes.manager.frontends.console import Console
    from links_and_nodes.manager.frontends.control import Control
    from links_and_nodes.tools.commands import Arg, Command, Local, Verb, register
    from links_and_nodes.tools.commands import table as registry

    def count(local: Local, args: dict[str, Any]) -> Iterator[dict[str, Any]]:
        for i in range(args["n"]):
            if local.stop.is_set():
                return
            yield {"i": i, "words": args["words"]}

    def script_args(words: str = "", times: int = 2) -> dict[str, Any]:
        return {"words": words, "n": times}

    entry = Command("count_demo", "count words", "demo", None,
                    (Arg("n", "int", "how many rows", default=2, low=1, flag="-n",
                         error="-n: {value!r} is not a count"),
                     Arg("words", "str", "the words left", default="", positional=True,
                         rest="join")),
                    result="rows: [{i, words}]", phrase="demo count", run=count,
                    streams=True, script_args=script_args,
                    console_format=lambda row, args: [f"{row['i']}: {row['words']}"])
    monkeypatch.setattr(registry, "_commands", dict(registry._commands))
    monkeypatch.setattr(registry, "_verbs", dict(registry._verbs))
    register(entry, Verb("demo", "demo commands", "demo", choose="command"))

    cmd, words = phrases.match(["demo", "count", "a", "-b", "-n", "3", "c"], "cli")
    assert parse_words(cmd, words, "cli") == {"n": 3, "words": "a -b c"}
    for bad, text in ((["demo"], "demo needs a command (one of: count)"),
                      (["demo", "x"], "unknown demo command 'x' (one of: count)")):
        with pytest.raises(ArgError, match=re.escape(text)):
            phrases.match(bad)
    with pytest.raises(ArgError, match="^-n: '0' is not a count$"):
        parse_words(cmd, ["-n", "0"])
    assert complete("demo ") == ["count"] and complete("demo count -") == ["-n"]

    control = Control(SimpleNamespace(), None, manager_address="127.0.0.1:1")  # type: ignore[arg-type]
    assert await control.handle({"op": "count_demo", "n": 2, "words": "x"}) == \
        {"ok": True, "rows": [{"i": 0, "words": "x"}, {"i": 1, "words": "x"}]}
    out = io.StringIO()
    console = Console(control, out)
    await console.execute("demo count hello world -n 2")
    for _ in range(200):
        if len(out.getvalue().splitlines()) == 2:
            break
        await asyncio.sleep(0.01)
    assert out.getvalue().splitlines() == ["0: hello world", "1: hello world"]

    mgr = Manager.__new__(Manager)
    mgr._local = Local(lambda op, **fields: {}, "127.0.0.1:1")
    assert mgr.count_demo("w", times=1) == [{"i": 0, "words": "w"}]
    with pytest.raises(ManagerError, match="is not a count"):
        mgr.count_demo("w", times=0)


def test_completion_from_the_table() -> None:
    assert complete("sta") == ["start", "status"]
    assert complete("output a -") == ["-f", "-n"]
    assert complete("topic ") == ["bw", "echo", "hz", "info"]
    assert complete("param s") == ["save", "set"]
    assert complete("help hi") == ["history"]


def test_fetch_max_is_the_logger_files_one() -> None:
    from links_and_nodes import logger_files
    from links_and_nodes.manager.loggers import commands as logger_control

    assert logger_control.FETCH_MAX == logger_files.FETCH_MAX


# ---- one running manager, every front end ---------------------------------------------------
class Fronts:
    """A manager with a console on a pipe; each front end asks it in turn."""

    def __init__(self, lab: pm.Lab) -> None:
        self.lab = lab
        self.address = f"127.0.0.1:{lab.manager_port}"
        body = "".join(
            f"process {name}\ncommand: {sys.executable} {CHILD} ready up-{name} "
            f"{lab.instance}\nready_regex: ^up\n\n" for name in ("a", "b"))
        self.proc = lab.manager(lab.write(body), "--webui", stdin=subprocess.PIPE)
        lab.wait_listening(self.proc)
        self.lines: queue.Queue[str] = queue.Queue()
        threading.Thread(target=self._read, daemon=True).start()
        webui = self.lines.get(timeout=LIMIT)
        assert webui.startswith("ln_manager: web UI on http://"), webui
        self.url = webui.rsplit(" ", 1)[1].rstrip("/")
        self.mgr = lab.connect()
        self.marks = 0
        self._ws: Any = None
        self._ws_id = 0
        self._stack = contextlib.ExitStack()

    def websocket(self, request: dict[str, Any]) -> dict[str, Any]:
        """The answer of a request through the web UI's WebSocket (docs/webui.md)."""
        if self._ws is None:
            from websockets.sync.client import connect

            with urllib.request.urlopen(self.url + "/", timeout=LIMIT) as page:
                cookie = page.headers["Set-Cookie"].split(";", 1)[0]
                body = page.read().decode()
            self.csrf = re.search(r'csrf-token" content="([^"]+)', body).group(1)  # type: ignore[union-attr]
            self._ws = self._stack.enter_context(connect(
                self.url.replace("http", "ws", 1) + "/ws", origin=self.url,
                additional_headers={"Cookie": cookie}, open_timeout=LIMIT))
        self._ws_id += 1
        self._ws.send(json.dumps({"id": self._ws_id, **request, "csrf": self.csrf}))
        while True:
            answer = json.loads(self._ws.recv(timeout=LIMIT))
            if answer.get("id") == self._ws_id:
                del answer["id"]
                return dict(answer)

    def close(self) -> None:
        self._stack.close()
        self.mgr.close()

    def _read(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            self.lines.put(line.rstrip("\n"))

    def console(self, line: str) -> list[str]:
        """The lines the console prints for `line` (up to a line that marks the end)."""
        self.marks += 1
        mark = f"end-of-{self.marks}"
        assert self.proc.stdin is not None
        self.proc.stdin.write(f"{line}\n{mark}\n")
        self.proc.stdin.flush()
        out = []
        while True:
            text = self.lines.get(timeout=LIMIT)
            if text == f"error: unknown command {mark!r} (try help)":
                return out
            out.append(text)

    def cli(self, *words: str) -> subprocess.CompletedProcess[str]:
        return subprocess.run([sys.executable, "-m", "links_and_nodes.manager", *words,
                               "--manager", self.address], capture_output=True, text=True,
                              env=self.lab.env, timeout=LIMIT)


@pytest.fixture(scope="module")
def fronts(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Fronts]:
    tmp = tmp_path_factory.mktemp("fronts")
    instance = f"ct-{uuid.uuid4().hex[:10]}"
    env = {**os.environ, "LN_RUNTIME_DIR": str(tmp / "run"),
           "LN_DAEMON_KEY_FILE": str(tmp / "keys" / "daemon.key"),
           "LN_ARBITER_PORT": str(pm.free_daemon_port()), "PYTHONUNBUFFERED": "1"}
    lab = pm.Lab(tmp, instance, env, pm.free_port(), int(env["LN_ARBITER_PORT"]))
    world = Fronts(lab)
    world.mgr.start("all")
    world.mgr.wait_ready("all", LIMIT)
    try:
        yield world
    finally:
        world.close()
        for proc in lab.managers:
            if proc.poll() is None:
                proc.terminate()
                proc.wait(timeout=LIMIT)
        for pid in lab.daemon_pids(all_forks=True) + pm.pids_with(instance):
            with contextlib.suppress(ProcessLookupError):
                os.kill(pid, signal.SIGKILL)


# (console line, CLI words, JSON request): read-only commands whose answer stays the same
READ_ONLY = [
    ("status", ["status"], {"op": "status"}),
    ("output a -n 2", ["output", "a", "-n", "2"], {"op": "output", "name": "a", "n": 2}),
    ("history b", ["history", "b"], {"op": "history", "name": "b"}),
    ("topics", ["topics"], {"op": "topics"}),
    ("services", ["services"], {"op": "services"}),
    ("network", ["network"], {"op": "network"}),
    ("pull", ["pull"], {"op": "pull"}),
    ("events", ["events"], {"op": "events"}),
]


@pytest.mark.parametrize(("line", "words", "request_"), READ_ONLY,
                         ids=[r[0].split()[0] for r in READ_ONLY])
def test_read_only_commands_answer_the_same_everywhere(fronts: Fronts, line: str,
                                                       words: list[str],
                                                       request_: dict[str, Any]) -> None:
    cmd = table.command(request_["op"])
    assert cmd is not None
    answer = fronts.mgr.command(**request_)  # JSON over the CONTROL connection
    if WEBSOCKETS:
        assert fronts.websocket(request_) == answer
    args = parse_words(cmd, line.split()[1:])
    view = cmd.console_format or json_lines
    expected_console = view(answer, args)
    if cmd.console_run is None:
        assert fronts.console(line) == expected_console
    else:  # output: its own view (each line after the process's name)
        assert fronts.console(line) == [f"a: {t['text']}" for t in answer["lines"]]
    done = fronts.cli(*words)
    assert done.returncode == 0, done.stderr
    cli_view = cmd.cli_format or view
    assert done.stdout.splitlines() == cli_view(answer, parse_words(cmd, words[1:], "cli"))
    as_json = fronts.cli(*words, "--json")
    assert as_json.returncode == 0, as_json.stderr
    json_view = cmd.json_view or (lambda r: {k: v for k, v in r.items() if k != "ok"})
    assert json.loads(as_json.stdout) == json_view(answer)
    method = getattr(fronts.mgr, cmd.script_name)
    script_args = {k: v for k, v in request_.items() if k != "op"}
    expected = cmd.script_result(answer) if cmd.script_result else \
        {k: v for k, v in answer.items() if k != "ok"}
    assert method(**script_args) == expected


def test_state_changing_commands_through_every_front_end(fronts: Fronts) -> None:
    mgr = fronts.mgr
    assert mgr.command("stop", target="b") == {"ok": True, "processes": ["b"]}
    assert mgr.state("b") == "stopped"
    if WEBSOCKETS:
        assert fronts.websocket({"op": "start", "target": "b"}) == {"ok": True,
                                                                    "processes": ["b"]}
        assert fronts.websocket({"op": "wait_ready", "target": "b", "timeout": LIMIT}) == \
            {"ok": True}
        assert fronts.websocket({"op": "stop", "target": "b"}) == {"ok": True,
                                                                   "processes": ["b"]}
    assert fronts.console("start b") == ["starting: b"]
    mgr.wait_ready("b", LIMIT)
    assert fronts.console("stop b") == ["stopped: b"]
    assert fronts.cli("start", "b", "--wait").stdout.splitlines() == ["ready: b"]
    assert fronts.cli("restart", "b").stdout.splitlines() == ["restarted: b"]
    mgr.wait_ready("b", LIMIT)
    assert mgr.stop("b") == ["b"]
    assert mgr.start("b") == ["b"]
    assert fronts.cli("wait-ready", "b", "--timeout", "60").stdout.splitlines() == ["ready"]
    assert fronts.console("restart b") == ["restarted: b"]
    mgr.wait_ready("all", LIMIT)
    assert [t["state"] for t in mgr.history("b")][-3:] == ["starting", "started", "ready"]


BAD = [  # (console line, CLI words, JSON request, the text every front end says)
    ("output a -n x", ["output", "a", "-n", "x"], {"op": "output", "name": "a", "n": "x"},
     '"n" must be 0..10000'),
    ("output a -n 10001", ["output", "a", "-n", "10001"],
     {"op": "output", "name": "a", "n": 10001}, '"n" must be 0..10000'),
    ("history", ["history"], {"op": "history"}, '"name" must be a non-empty string'),
    ("stop ''", ["stop", ""], {"op": "stop", "target": ""},
     '"target" must be a process, a group or "all"'),
    ("history nope", ["history", "nope"], {"op": "history", "name": "nope"},
     "no process named 'nope'"),
]


@pytest.mark.parametrize(("line", "words", "request_", "text"), BAD,
                         ids=[b[0] for b in BAD])
def test_a_bad_argument_is_the_same_text_everywhere(fronts: Fronts, line: str,
                                                    words: list[str],
                                                    request_: dict[str, Any],
                                                    text: str) -> None:
    with pytest.raises(ManagerError) as refused:
        fronts.mgr.command(**request_)
    assert str(refused.value) == text
    if WEBSOCKETS:
        assert fronts.websocket(request_) == {"ok": False, "error": text}
    assert fronts.console(line) == [f"error: {text}"]
    done = fronts.cli(*words)
    assert done.returncode in (1, 2)
    assert done.stderr.splitlines() == [f"ln_manager {words[0]}: error: {text}"]


def test_logger_words_answer_the_same_everywhere(fronts: Fronts) -> None:
    """The `logger` family: words in the console and `ln_manager logger`, JSON over CONTROL
    and the WebSocket, the scripting API: one table entry each, the same answers."""
    from links_and_nodes.manager.loggers.views import format_result

    mgr = fronts.mgr
    assert fronts.console("logger ctlog add 'ctl.*' 50 --divisor 2") == \
        format_result("logger_add", {}, mgr.command("logger_status", name="ctlog"))
    status = mgr.command("logger_status", name="ctlog")
    assert status["patterns"] == [{"pattern": "ctl.*", "depth": 50, "divisor": 2, "span": 0}]
    if WEBSOCKETS:
        assert fronts.websocket({"op": "logger_status", "name": "ctlog"}) == status
    assert mgr.logger_status("ctlog") == {k: v for k, v in status.items() if k != "ok"}
    expected = format_result("logger_status", {}, status)
    assert fronts.console("logger ctlog status") == expected
    done = fronts.cli("logger", "ctlog", "status")
    assert done.returncode == 0 and done.stdout.splitlines() == expected, done.stderr
    assert json.loads(fronts.cli("logger", "ctlog", "status", "--json").stdout) == status
    listing = mgr.command("logger_list")
    assert fronts.console("logger") == format_result("logger_list", {}, listing)
    assert fronts.cli("logger").stdout.splitlines() == format_result("logger_list", {}, listing)
    assert fronts.cli("logger", "ctlog", "enable", "--keep").stdout.splitlines() == \
        ["enabled: logger ctlog"]
    assert fronts.console("logger ctlog disable") == ["disabled: logger ctlog"]
    assert fronts.console("logger ctlog remove 'ctl.*'") == \
        ["removed: 'ctl.*' of logger ctlog"]
    text = '"depth" must be an integer >= 1'
    with pytest.raises(ManagerError, match=text):
        mgr.command("logger_add", name="ctlog", topic="x", depth=0)
    if WEBSOCKETS:
        assert fronts.websocket({"op": "logger_add", "name": "ctlog", "topic": "x",
                                 "depth": 0}) == {"ok": False, "error": text, "code": "EINVAL"}
    assert fronts.console("logger ctlog add x 0") == [f"error: {text}"]
    done = fronts.cli("logger", "ctlog", "add", "x", "0")
    assert done.returncode == 2 and done.stderr.splitlines() == \
        [f"ln_manager logger add: error: {text}"]


def test_console_on_a_terminal_completes_with_tab(tmp_path: Path) -> None:
    """On a terminal the console reads with readline: Tab completes from the table."""
    import pty
    import select
    import time

    port = pm.free_port()
    config = tmp_path / "t.lnc"
    config.write_text(f"instance\nname: ct-tty-{uuid.uuid4().hex[:8]}\n"
                      f"manager: 127.0.0.1:{port}\n")
    env = {**os.environ, "LN_RUNTIME_DIR": str(tmp_path / "run"),
           "LN_DAEMON_KEY_FILE": str(tmp_path / "daemon.key"),
           "LN_ARBITER_PORT": str(pm.free_daemon_port())}
    main, side = pty.openpty()
    proc = subprocess.Popen([sys.executable, "-m", "links_and_nodes.manager", "-c",
                             str(config)], stdin=side, stdout=side, stderr=side, env=env,
                            start_new_session=True)
    os.close(side)
    seen = ""

    def until(text: str) -> None:
        nonlocal seen
        end = time.monotonic() + LIMIT
        while text not in seen:
            assert time.monotonic() < end, f"no {text!r} in {seen!r}"
            if select.select([main], [], [], 0.1)[0]:
                seen += os.read(main, 4096).decode(errors="replace")

    try:
        until("listening on")
        os.write(main, b"sta\t\t")
        until("start   status")  # both, as readline lists them
        os.write(main, b"\x15help hi\t\n")  # Ctrl-U, then completed to `help history`
        until("usage: history NAME")
        os.write(main, b"quit\n")
        assert proc.wait(timeout=LIMIT) == 0
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        os.close(main)
