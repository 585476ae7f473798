"""The introspection commands in the console of `ln_manager -c FILE` (stdin/stdout of a real
manager whose md search path comes from the configuration's add_message_definition_dir):
the same output as the client commands; `topic echo|hz` print in the background until done
or the next command line; errors are `error: ...` lines and the manager goes on."""

from __future__ import annotations

import json
import os
import re
import subprocess
import uuid
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path

import pytest
from console_manager import Console, console_manager
from polling import free_daemon_port, free_port

from .conftest import LIMIT, MDS, PERIOD, spawn, stop
from .probe_publisher import probe_values

HEADER = re.compile(r"^--- seq (\d+), published \d+\.\d{9}$")


@dataclass
class ConsoleManager:
    """The console, with the clients' environment and the test processes it started."""

    console: Console
    env: dict[str, str]
    procs: list[subprocess.Popen[str]] = field(default_factory=list)

    @property
    def address(self) -> str:
        return self.console.address

    @property
    def seen(self) -> list[str]:
        return self.console.seen

    def send(self, line: str) -> None:
        self.console.send(line)

    def expect(self, accept: Callable[[str], bool], what: str) -> list[str]:
        return self.console.expect(accept, what)

    def publisher(self) -> None:
        env = {k: v for k, v in self.env.items() if k != "LN_MESSAGE_DEFINITION_DIRS"}
        self.procs.append(spawn(self.address, env, "probe_publisher.py", "probe.state",
                                str(PERIOD), str(MDS)))

    def provider(self) -> None:
        self.procs.append(spawn(self.address, self.env, "adjust_provider.py", "probe.adjust",
                                str(MDS)))


@pytest.fixture
def console(tmp_path: Path) -> Iterator[ConsoleManager]:
    instance = f"ic{os.getpid()}x{uuid.uuid4().hex[:8]}"
    port, daemon_port = free_port(), free_daemon_port()
    config = tmp_path / "introspect.lnc"
    config.write_text(f"instance\nname: {instance}\nmanager: 127.0.0.1:{port}\n\n"
                      f"add_message_definition_dir: {MDS}\n")
    env = {k: v for k, v in os.environ.items() if k != "LN_MESSAGE_DEFINITION_DIRS"}
    env.update(LN_RUNTIME_DIR=str(tmp_path / "run"),
               LN_DAEMON_KEY_FILE=str(tmp_path / "daemon.key"),
               LN_ARBITER_PORT=str(daemon_port), PYTHONUNBUFFERED="1")
    with console_manager(config, instance, port, daemon_port, env, LIMIT) as con:
        mgr = ConsoleManager(con, {**env, "LN_MANAGER": con.address})
        try:
            yield mgr
        finally:
            stop(mgr.procs)


def test_echo_with_n_prints_decoded_samples(console: ConsoleManager) -> None:
    console.publisher()
    console.send("topic echo probe.state -n 2 --json")
    lines = console.expect(lambda line: line.startswith("{"), "a first sample")
    lines += console.expect(lambda line: line.startswith("{"), "a second sample")
    records = [json.loads(line) for line in lines]
    assert len(records) == 2
    for record in records:
        assert record["data"] == probe_values(record["seq"])
    console.send("topic echo probe.state -n 1")
    block = console.expect(lambda line: line.startswith("trace: "), "a sample as text")
    seq = int(HEADER.match(block[0]).group(1))  # type: ignore[union-attr]
    assert block[1:3] == [f"count: {seq}", "q: [" + ", ".join(
        repr(seq + j / 8) for j in range(7)) + "]"]


def test_following_echo_stops_at_the_next_command(console: ConsoleManager) -> None:
    console.publisher()
    console.send("topic echo probe.state --field count")
    console.expect(lambda line: line.isdigit(), "a first count")
    console.expect(lambda line: line.isdigit(), "a second count")
    console.send("md show lntest/probe")
    text = (MDS / "lntest" / "probe").read_text().splitlines()
    console.expect(lambda line: line == text[0], "the md's first line")
    console.expect(lambda line: line == text[-1], "the md's last line")
    console.send("topic info nope")
    after = console.expect(lambda line: line.startswith("error: "), "the error")
    # from the md's first line on, no count came any more
    start = console.seen.index(text[0])
    assert not [line for line in console.seen[start:] if line.isdigit()]
    assert after[-1] == "error: no topic 'nope'"


def test_hz_bw_info_and_service_call(console: ConsoleManager) -> None:
    console.publisher()
    console.provider()
    console.send("topic hz probe.state -n 4")
    console.expect(lambda line: re.match(r"^rate: .* window: 4 samples, \d+ periods, \d+ "
                                         r"missed$", line) is not None, "the rate line")
    console.send("topic bw probe.state -n 3")
    console.expect(lambda line: re.match(r"^bandwidth: .* \(940 B x .* window: 3 samples",
                                         line) is not None, "the bandwidth line")
    console.send("topic info probe.state")
    info = console.expect(lambda line: line.startswith("subscribers: "), "the subscribers")
    assert info[1].startswith("md: lntest/probe (layout hash 0x")
    assert any(line.startswith("  probe_pub (pid ") for line in info)
    console.send("service call probe.adjust values: [1, 2, 3], name: 'x', tags: [a]")
    response = console.expect(lambda line: line.startswith("count: "), "the response")
    assert response[:2] == ["total: 6.0", 'text: "x: a"'] and response[-1] == "count: 1"
    console.send("service call probe.adjust name: fail")
    console.expect(lambda line: line == "error: service 'probe.adjust' (provider 'adjuster') "
                   "answered with an error: asked to fail", "the error response")


def test_errors_are_lines_and_the_manager_goes_on(console: ConsoleManager) -> None:
    for command, error in [
        ("topic echo nope -n 1", "error: no topic 'nope'"),
        ("topic", "error: topic needs a command (one of: bw, echo, hz, info)"),
        ("md show lntest/nope", "error: message definition 'lntest/nope' not found"),
        ("service call nope a: 1", "error: no service 'nope'"),
        ("topic echo x --bogus", "error: unknown option '--bogus'"),
    ]:
        console.send(command)
        [line] = console.expect(lambda line: line.startswith("error: "), command)
        assert line.startswith(error), line
    console.send("topic hz nope")  # following commands fail in their worker, also one line
    console.expect(lambda line: line == "error: no topic 'nope'", "the hz error")
    console.send("status")
    console.expect(lambda line: line.startswith("process"), "the status table")


def test_quit_while_following(console: ConsoleManager) -> None:
    console.publisher()
    console.send("topic hz probe.state")
    console.expect(lambda line: line.startswith("rate: "), "a rate line")
    console.send("quit")
    assert console.console.proc.wait(LIMIT) == 0


def test_graph_in_the_console(console: ConsoleManager) -> None:
    """`graph` (docs/introspection.md): the same command in the console, here as DOT."""
    console.publisher()
    console.send("graph --dot --window 0")
    lines = console.expect(lambda line: line == "}", "the end of the DOT text")
    start = lines.index("digraph links_and_nodes {")
    # the manager's first look: no rates yet, so no labels
    assert '  "c:probe_pub" -> "t:probe.state";' in lines[start:]
    console.send("graph --window x")
    assert console.expect(lambda line: line.startswith("error: "), "the error")[-1] == \
        "error: --window: 'x' is not a number of seconds 0..10"
