"""Process sections: every key read into the model exactly, list keys replaced and
extended, value syntaxes (durations, sizes, signals, policies, CPU lists, limits)."""

from __future__ import annotations

import signal
from pathlib import Path

import pytest

from links_and_nodes.manager.config import parse_text
from links_and_nodes.manager.config.model import (
    Config,
    Instance,
    OnLimit,
    OutputLog,
    Policy,
    Process,
    ResourceLimit,
    Restart,
    State,
    Watchdog,
)

from .helpers import HEAD, cfg, load_files, loc


def test_minimal_file(tmp_path: Path) -> None:
    config = load_files(tmp_path, {"main.lnc": HEAD})
    main = tmp_path / "main.lnc"
    assert config == Config(files=[str(main)],
                            instance=Instance("demo", ":54414", loc(main, 1, 1)))


def test_every_process_key(tmp_path: Path) -> None:
    (tmp_path / "md").mkdir()
    config = load_files(tmp_path, {"main.lnc": cfg("""
        process arm
            node: robot_pc
            command: /opt/arm/bin/arm --rate 1000
            environment: LANG=C
            add environment: PYTHONIOENCODING=utf-8, OMP_PLACES=0,1
            pass_environment: HOME, DISPLAY
            add pass_environment: XAUTHORITY
            change_directory: work
            depends_on: net
            start_before: setup
            start_on_ready: viewer
            ready_regex: ^arm ready
            ready_time: 500ms
            ready_on_topic: robot.arm.state
            ready_on_service: robot.arm.move
            term_signal: SIGINT
            term_timeout: 2.5
            policy: SCHED_FIFO
            priority: 80
            affinity: 2,0-1,7
            set_resource_limits: core:unlimited, nofile:1024:4096
            add set_resource_limits: memlock:64M
            output_logfile: logs/arm.log
            output_logfile_size_limit: 2M
            output_logfile_keep_count: 5
            max_output_lines: 200
            output_encoding: latin-1
            flags: no_pty
            add flags: forward_x11 start_in_shell
            restart: on-failure
            restart_limit: 3
            restart_delay: 1min
            watchdog_topic: robot.arm.state, 50
            add_message_definition_dir: md
        process setup
            command: setup.sh
        process viewer
            command: viewer
        state net
            check: ping -c1 robot
        """)})
    main = tmp_path / "main.lnc"
    assert config.processes["arm"] == Process(
        name="arm", location=loc(main, 4, 1), command="/opt/arm/bin/arm --rate 1000",
        node="robot_pc",
        environment={"LANG": "C", "PYTHONIOENCODING": "utf-8", "OMP_PLACES": "0,1"},
        pass_environment=["HOME", "DISPLAY", "XAUTHORITY"],
        change_directory=str(tmp_path / "work"),
        depends_on=["net"], start_before=["setup"], start_on_ready=["viewer"],
        ready_regex="^arm ready", ready_time=0.5, ready_on_topic="robot.arm.state",
        ready_on_service="robot.arm.move", term_signal=int(signal.SIGINT), term_timeout=2.5,
        policy=Policy.FIFO, priority=80, affinity=[0, 1, 2, 7],
        resource_limits=[ResourceLimit("core", None, None), ResourceLimit("nofile", 1024, 4096),
                         ResourceLimit("memlock", 64 << 20, 64 << 20)],
        output_log=OutputLog(str(tmp_path / "logs/arm.log"), 2 << 20, 5),
        max_output_lines=200, output_encoding="iso8859-1",
        flags={"no_pty", "forward_x11", "start_in_shell"},
        restart=Restart.ON_FAILURE, restart_limit=3, restart_delay=60.0,
        watchdog=Watchdog("robot.arm.state", 50.0),
        message_definition_dirs=[str(tmp_path / "md")])
    assert list(config.processes) == ["arm", "setup", "viewer"]
    assert config.states == {"net": State("net", loc(main, 42, 1), "ping -c1 robot")}
    assert config.message_definition_dirs == []


def test_defaults(tmp_path: Path) -> None:
    config = load_files(tmp_path, {"main.lnc": HEAD + "process p\ncommand: p\n"})
    assert config.processes["p"] == Process("p", loc(tmp_path / "main.lnc", 4, 1), "p")


def test_list_keys_are_replaced_and_extended(tmp_path: Path) -> None:
    config = load_files(tmp_path, {"main.lnc": cfg("""
        process p
            command: p
            flags: no_pty
            add flags: use_vte
            flags: forward_x11
            environment: A=1
            add environment: B=2
            environment: C=3
            depends_on: q
            depends_on: r
            add depends_on: q, r
        process q
            command: q
        process r
            command: r
        """)})
    p = config.processes["p"]
    assert p.flags == {"forward_x11"}
    assert p.environment == {"C": "3"}
    assert p.depends_on == ["r", "q"]


def test_scalar_keys_take_the_last_value(tmp_path: Path) -> None:
    config = load_files(tmp_path, {"main.lnc": cfg("""
        process p
            command: first
            node: a
            command: second
            node: b
        """)})
    assert (config.processes["p"].command, config.processes["p"].node) == ("second", "b")


def test_block_values(tmp_path: Path) -> None:
    config = load_files(tmp_path, {"main.lnc": cfg("""
        process p
            command: [
                /bin/tool
                  --a # not a comment in a block
                # a comment line in a block

                --b
            ]
            environment: [
                A=1
                B=x y, z
            ]
            add depends_on: [
                q, r
                s
            ] # done
        process q
            command: q
        process r
            command: r
        process s
            command: s
        """)})
    p = config.processes["p"]
    assert p.command == "/bin/tool\n--a # not a comment in a block\n--b"
    assert p.environment == {"A": "1", "B": "x y, z"}
    assert p.depends_on == ["q", "r", "s"]


def test_comments_and_quotes(tmp_path: Path) -> None:
    config = load_files(tmp_path, {"main.lnc": cfg(r"""
        # a comment line
        process p  # trailing comment after a name
            command: echo "#1 is a \"hash\"" # but this is a comment
            node: "robot"
            ready_regex: "^ready #[0-9]+$"
            environment: "GREETING=hello, world"
        """)})
    p = config.processes["p"]
    assert p.command == r'echo "#1 is a \"hash\""'
    assert p.node == "robot"
    assert p.ready_regex == "^ready #[0-9]+$"
    assert p.environment == {"GREETING": "hello, world"}


@pytest.mark.parametrize(("text", "expected"), [
    ("term_timeout: 3", 3.0), ("term_timeout: 1.5s", 1.5), ("term_timeout: 250ms", 0.25),
    ("term_timeout: 2min", 120.0), ("term_timeout: 1h", 3600.0), ("term_timeout: .5", 0.5),
])
def test_durations(text: str, expected: float) -> None:
    config = parse_text(HEAD + f"process p\ncommand: p\n{text}\n", "/nowhere/x.lnc")
    assert config.processes["p"].term_timeout == expected


@pytest.mark.parametrize(("text", "expected"), [
    ("4096", 4096), ("512K", 512 << 10), ("10M", 10 << 20), ("1G", 1 << 30),
    ("3 MiB", 3 << 20), ("7kb", 7 << 10), ("9B", 9),
])
def test_sizes(text: str, expected: int) -> None:
    config = parse_text(HEAD + f"process p\ncommand: p\noutput_logfile: /l\n"
                        f"output_logfile_size_limit: {text}\n", "/nowhere/x.lnc")
    assert config.processes["p"].output_log == OutputLog("/l", expected)


@pytest.mark.parametrize(("text", "expected"), [
    ("SIGINT", signal.SIGINT), ("int", signal.SIGINT), ("KILL", signal.SIGKILL),
    ("15", signal.SIGTERM), ("SIGUSR1", signal.SIGUSR1),
])
def test_signals(text: str, expected: int) -> None:
    config = parse_text(HEAD + f"process p\ncommand: p\nterm_signal: {text}\n", "/n/x.lnc")
    assert config.processes["p"].term_signal == int(expected)


@pytest.mark.parametrize(("policy", "priority", "expected"), [
    ("SCHED_OTHER", "-20", Policy.OTHER), ("other", "19", Policy.OTHER),
    ("FIFO", "1", Policy.FIFO), ("sched_rr", "99", Policy.RR), ("RR", "50", Policy.RR),
])
def test_policies(policy: str, priority: str, expected: Policy) -> None:
    config = parse_text(HEAD + f"process p\ncommand: p\npolicy: {policy}\n"
                        f"priority: {priority}\n", "/n/x.lnc")
    p = config.processes["p"]
    assert (p.policy, p.priority) == (expected, int(priority))


def test_resource_limit_names_and_sizes() -> None:
    config = parse_text(HEAD + "process p\ncommand: p\nset_resource_limits: RLIMIT_STACK:8M:"
                        "infinity, rtprio:99, nice:0:10\n", "/n/x.lnc")
    assert config.processes["p"].resource_limits == [
        ResourceLimit("stack", 8 << 20, None), ResourceLimit("rtprio", 99, 99),
        ResourceLimit("nice", 0, 10)]


def test_output_log_settings_before_the_path(tmp_path: Path) -> None:
    config = load_files(tmp_path, {"main.lnc": cfg("""
        process p
            command: p
            output_logfile_keep_count: 0
            output_logfile: /var/log/p.log
        process q
            command: q
            output_logfile_size_limit: 1K
        """)})
    assert config.processes["p"].output_log == OutputLog("/var/log/p.log", 10 << 20, 0)
    assert config.processes["q"].output_log is None


def test_gui_keys_of_the_original_are_ignored(tmp_path: Path) -> None:
    config = load_files(tmp_path, {"main.lnc": cfg("""
        process p
            command: p
            vte_color_style: dark
            line_highlight_fg_color: red
            line_highlight_bg_color: blue
            add line_highlight_regexes: ERROR
            bugtracker_url: https://example.org
            mantis_project_id: 4
            notebook: robots
            documentation: README.md
            warning_regex: WARN
            warning_msg: look
            max_output_frequency: 10
            output_buffer_size: 4096
            max_queued_output_bytes: 100
        """)})
    assert config.processes["p"] == Process("p", loc(tmp_path / "main.lnc", 4, 1), "p")


def test_relative_paths_resolve_against_the_including_files_directory(tmp_path: Path) -> None:
    config = load_files(tmp_path, {
        "main.lnc": HEAD + "include sub/p.inc.lnc\n",
        "sub/p.inc.lnc": """
            process p
                command: p
                change_directory: ../run
                output_logfile: log/p.log
            process q
                command: q
                change_directory: /abs
                output_logfile: ~/q.log
            """})
    p, q = config.processes["p"], config.processes["q"]
    assert p.change_directory == str(tmp_path / "run")
    assert p.output_log == OutputLog(str(tmp_path / "sub/log/p.log"))
    assert (q.change_directory, q.output_log) == ("/abs", OutputLog("~/q.log"))


def test_resource_limit_keys() -> None:
    config = parse_text(HEAD + "process p\ncommand: p\nmax_rss: 512M\nmax_cpu: 150.5\n"
                        "on_limit: restart\nprocess q\ncommand: q\n", "/n/x.lnc")
    p, q = config.processes["p"], config.processes["q"]
    assert (p.max_rss, p.max_cpu, p.on_limit) == (512 << 20, 150.5, OnLimit.RESTART)
    assert (q.max_rss, q.max_cpu, q.on_limit) == (None, None, OnLimit.WARN)
