"""The structure of a configuration: instance, defines and `%()` evaluation, hosts and
node_map, includes, name prefixes, templates, states and groups."""

from __future__ import annotations

import os
import socket
import zlib
from pathlib import Path

import pytest

from links_and_nodes.manager.config import ConfigError, load, parse_text
from links_and_nodes.manager.config.expand import port_from_string
from links_and_nodes.manager.config.model import Group, Host, Instance, State

from .helpers import HEAD, cfg, load_files, loc, write


def test_instance_keys(tmp_path: Path) -> None:
    config = load_files(tmp_path, {"main.lnc": """
        # robot
        instance
        name: lab robot
        manager: robot-pc:%(get_port_from_string "%(instance_name)")
        documentation: https://example.org/robot
        webui_auth_file: auth/users
        enable_auto_groups: true
        """})
    port = port_from_string("lab robot")
    assert config.instance == Instance("lab robot", f"robot-pc:{port}",
                                       loc(tmp_path / "main.lnc", 2, 1),
                                       "https://example.org/robot",
                                       str(tmp_path / "auth/users"))


def test_port_from_string_formula() -> None:
    for text in ("", "robot", "lab robot", "ünïcode"):
        port = port_from_string(text)
        assert port == 20000 + zlib.crc32(text.encode()) % 12000
        assert 20000 <= port < 32000
    assert port_from_string("robot") == 25188  # the formula must not change


def test_manager_override_and_builtin(tmp_path: Path) -> None:
    body = HEAD + "defines\nm: %(manager)\n"
    config = load_files(tmp_path, {"main.lnc": body}, manager="10.0.0.1:6000")
    assert config.instance.manager == "10.0.0.1:6000"
    assert config.defines == {"m": "10.0.0.1:6000"}
    config = load_files(tmp_path, {"main.lnc": body})
    assert config.defines == {"m": f"{socket.gethostname()}:54414"}
    with pytest.raises(ValueError, match="HOST:PORT"):
        load(tmp_path / "main.lnc", manager="nope")


def test_defines_are_position_dependent_and_evaluated(tmp_path: Path) -> None:
    config = load_files(tmp_path, {"main.lnc": cfg("""
        defines
        robot: rollin
        message: hello %(robot)
        %(robot)_home: /home/%(robot)
        robot: justin
        process p
            command: echo %(message) %(robot) %(rollin_home)
        defines
        later: %(robot)
        """)})
    assert config.processes["p"].command == "echo hello rollin justin /home/rollin"
    assert config.defines == {"robot": "justin", "message": "hello rollin",
                              "rollin_home": "/home/rollin", "later": "justin"}


def test_caller_defines_win_over_the_files(tmp_path: Path) -> None:
    config = load_files(tmp_path, {"main.lnc": cfg("""
        defines
        robot: rollin
        ifndef speed: speed: slow
        ifdef robot: add_message_definition_dir: .
        """)}, defines={"robot": "sim", "speed": "fast"})
    assert config.defines == {"robot": "sim", "speed": "fast"}
    assert config.message_definition_dirs == [str(tmp_path)]
    with pytest.raises(ValueError, match="bad define name"):
        load(tmp_path / "main.lnc", defines={"a b": "c"})
    with pytest.raises(ValueError, match="bad define name"):
        load(tmp_path / "main.lnc", defines={"CURDIR": "c"})


def test_ifdef_and_ifndef(tmp_path: Path) -> None:
    config = load_files(tmp_path, {"main.lnc": cfg("""
        defines
        sim: 1
        process p
            command: p
            ifdef sim: node: simhost
            ifndef sim: node: robot
            ifdef nothing: add flags: no_pty
            ifndef nothing: ifdef sim: add flags: use_vte
            ifdef sim: environment: [
                A=1
            ]
        """)})
    p = config.processes["p"]
    assert (p.node, p.flags, p.environment) == ("simhost", {"use_vte"}, {"A": "1"})


def test_builtins_and_functions(tmp_path: Path) -> None:
    config = load_files(tmp_path, {"sub/main.lnc": cfg("""
        defines
        dir: %(CURDIR)
        file: %(CURRENT)
        inst: %(instance_name)
        host: %(hostname)
        home: %(env HOME_OF_TEST)
        quoted: %(env NOT_SET_IN_TEST, "a, b")
        up: %(dirname %(CURDIR))
        sub: %(subst "rollin", "justin", "hello rollin rollin")
        demo_name: x
        nested: %(%(inst)_name)
        port: %(get_port_from_string %(inst))
        process arm
            command: %(_PROCESS) %(_FULL_PROCESS)
        defines
        last: %(_PROCESS)
        """)}, env={"HOME_OF_TEST": "/home/t"})
    d = config.defines
    assert d["dir"] == str(tmp_path / "sub")
    assert d["file"] == str(tmp_path / "sub/main.lnc")
    assert (d["inst"], d["host"], d["home"]) == ("demo", socket.gethostname(), "/home/t")
    assert d["quoted"] == "a, b"
    assert (d["up"], d["sub"]) == (str(tmp_path), "hello justin justin")
    assert d["port"] == str(port_from_string("demo"))
    assert d["last"] == "arm"
    assert d["nested"] == "x"
    assert config.processes["arm"].command == "arm arm"


def test_env_with_three_arguments_is_an_error(tmp_path: Path) -> None:
    path = write(tmp_path, {"main.lnc": cfg("defines\nx: %(env A, b, c)\n")})
    with pytest.raises(ConfigError) as err:
        load(path, env={})
    assert str(err.value) == (f"{path}:5:4: 'env' takes NAME or NAME, DEFAULT, got 3 "
                              "arguments")


def test_builtin_defaults_to_os_environ(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("LNC_TEST_VALUE", "from-os")
    path = write(tmp_path, {"main.lnc": cfg("defines\nx: %(env LNC_TEST_VALUE)\n")})
    assert load(path).defines == {"x": "from-os"}


def test_hosts_and_node_map(tmp_path: Path) -> None:
    config = load_files(tmp_path, {"main.lnc": cfg("""
        hosts
        robot-pc: eth0:192.168.0.2, process_start_rate_limit:5, daemon_port:5000
        hosts
        robot-pc: wifi:10.0.0.2, daemon_start_script:"/opt/ln/start, daemon.sh"
        laptop: lan:10.0.0.3
        node_map
        arm_node: robot-pc
        viewer_node: laptop
        """)})
    main = tmp_path / "main.lnc"
    assert config.hosts == {
        "robot-pc": Host("robot-pc", loc(main, 5, 1),
                         {"eth0": "192.168.0.2", "wifi": "10.0.0.2"}, 5.0, 5000,
                         "/opt/ln/start, daemon.sh"),
        "laptop": Host("laptop", loc(main, 8, 1), {"lan": "10.0.0.3"}),
    }
    assert config.node_map == {"arm_node": "robot-pc", "viewer_node": "laptop"}


def test_includes_share_the_section_and_are_listed(tmp_path: Path) -> None:
    config = load_files(tmp_path, {
        "main.lnc": cfg("""
            process arm
                command: arm
                include parts/env.inc.lnc
                add environment: AFTER=1
            optional_include parts/missing.inc.lnc
            include_glob parts/*.lnc !parts/env.inc.lnc !parts/_*.lnc
            include "%(CURDIR)/parts/last.inc"
            """),
        "parts/env.inc.lnc": "add environment: FROM_INCLUDE=1\n",
        "parts/b.lnc": "process b\n    command: b\n",
        "parts/a.lnc": "process a\n    command: a\n",
        "parts/_skip.lnc": "process skip\n    command: skip\n",
        "parts/last.inc": "process last\n    command: last\n",
    })
    assert config.processes["arm"].environment == {"FROM_INCLUDE": "1", "AFTER": "1"}
    assert list(config.processes) == ["arm", "a", "b", "last"]
    assert config.files == [str(tmp_path / f) for f in (
        "main.lnc", "parts/env.inc.lnc", "parts/a.lnc", "parts/b.lnc", "parts/last.inc")]


def test_recursive_include_glob_skips_the_including_file(tmp_path: Path) -> None:
    config = load_files(tmp_path, {
        "main.lnc": cfg("include_glob **/*.lnc\n"),
        "x/deep/p.lnc": "process p\n    command: p\n",
    })
    assert list(config.processes) == ["p"]


def test_name_prefixes(tmp_path: Path) -> None:
    config = load_files(tmp_path, {
        "main.lnc": cfg("""
            push_name_prefix: robot
            include arm.inc.lnc
            process base
                command: base
                depends_on: arm/driver, camera
            pop_name_prefix robot
            process camera
                command: camera
            process ui
                command: ui
                depends_on: robot/base, robot/arm/driver
            """),
        "arm.inc.lnc": """
            push_name_prefix: arm
            process driver
                command: driver
            """,
    })
    assert list(config.processes) == ["robot/arm/driver", "robot/base", "camera", "ui"]
    assert config.processes["robot/base"].depends_on == ["robot/arm/driver", "camera"]
    assert config.processes["ui"].depends_on == ["robot/base", "robot/arm/driver"]


def test_references_prefer_the_innermost_prefix(tmp_path: Path) -> None:
    config = load_files(tmp_path, {"main.lnc": cfg("""
        process db
            command: outer db
        push_name_prefix: robot
        process db
            command: robot db
        process app
            command: app
            depends_on: db
        """)})
    assert config.processes["robot/app"].depends_on == ["robot/db"]


def test_templates(tmp_path: Path) -> None:
    config = load_files(tmp_path, {
        "main.lnc": cfg("""
            include lib/templates.inc.lnc
            template rt(prio, policy=FIFO)
                policy: %(policy)
                priority: %(prio)
            process_template with_rt(prio)
                use_template: rt(%(prio))
                add flags: no_pty
            process arm
                command: arm
                use_template: with_rt(90)
                use_template: here("a, b")
                priority: 91
            process cam
                use_template: rt(5, RR)
                command: cam
            """),
        "lib/templates.inc.lnc": """
            template here(what, dir=%(CURDIR))
                add environment: WHAT=%(what)
                add environment: DIR=%(dir)
                change_directory: %(CURDIR)
            """,
    })
    arm, cam = config.processes["arm"], config.processes["cam"]
    assert (arm.policy.value, arm.priority, arm.flags) == ("SCHED_FIFO", 91, {"no_pty"})
    assert arm.environment == {"WHAT": "a, b", "DIR": str(tmp_path / "lib")}
    assert arm.change_directory == str(tmp_path / "lib")
    assert (cam.policy.value, cam.priority) == ("SCHED_RR", 5)


def test_templates_resolve_in_the_prefix_scope(tmp_path: Path) -> None:
    config = load_files(tmp_path, {"main.lnc": cfg("""
        template node_t
            node: global
        push_name_prefix: robot
        template node_t
            node: robot_pc
        process a
            command: a
            use_template: node_t
        push_name_prefix: arm
        process b
            command: b
            use_template: node_t
        pop_name_prefix
        pop_name_prefix
        process c
            command: c
            use_template: node_t
        process d
            command: d
            use_template: robot/node_t
        """)})
    nodes = {name: p.node for name, p in config.processes.items()}
    assert nodes == {"robot/a": "robot_pc", "robot/arm/b": "robot_pc", "c": "global",
                     "d": "robot_pc"}


def test_a_template_body_ends_at_a_file_directive(tmp_path: Path) -> None:
    config = load_files(tmp_path, {"main.lnc": cfg("""
        template t
            node: x
        push_name_prefix: robot
        process p
            command: p
            use_template: t
        """)})
    assert list(config.processes) == ["robot/p"]


def test_states(tmp_path: Path) -> None:
    config = load_files(tmp_path, {"main.lnc": cfg("""
        state mounted
            check: mountpoint -q /data
            up: [
                mount /data
            ]
            down: umount /data
            node: storage
            min_check_interval: 2.5
            documentation: mounts the data disk
        process p
            command: p
            depends_on: mounted
        """)})
    assert config.states == {"mounted": State(
        "mounted", loc(tmp_path / "main.lnc", 4, 1), "mountpoint -q /data", "mount /data",
        "umount /data", "storage", 2.5)}
    assert config.processes["p"].depends_on == ["mounted"]


def test_groups(tmp_path: Path) -> None:
    config = load_files(tmp_path, {"main.lnc": cfg("""
        process watcher_a
            command: a
        process watcher_b
            command: b
        process other
            command: o
        state net
            check: true
        push_name_prefix: robot
        process watcher_c
            command: c
        group local
            members: watcher_*
        pop_name_prefix
        group watchers
            add members: watcher_*, !watcher_b
            add members: net
            flags: sorted, show_opened
        group all
            members: watchers, robot/local, other, *
        group empty
            flags: allow_empty
            members: nothing_*, missing
        """)})
    main = tmp_path / "main.lnc"
    assert config.groups == {
        "robot/local": Group("robot/local", loc(main, 15, 1), ["robot/watcher_c"]),
        "watchers": Group("watchers", loc(main, 18, 1), ["watcher_a", "net"],
                          {"sorted", "show_opened"}),
        "all": Group("all", loc(main, 22, 1),
                     ["watchers", "robot/local", "other", "watcher_a", "watcher_b", "net",
                      "robot/watcher_c"]),
        "empty": Group("empty", loc(main, 24, 1), [], {"allow_empty"}),
    }


def test_message_definition_dirs(tmp_path: Path) -> None:
    for d in ("md", "inc/md2", "inc/pmd"):
        (tmp_path / d).mkdir(parents=True)
    config = load_files(tmp_path, {
        "main.lnc": cfg("add_message_definition_dir: md\ninclude inc/x.inc.lnc\n"
                        "add_message_definition_dir: %(CURDIR)/md\n"),
        "inc/x.inc.lnc": "add_message_definition_dir: md2\nprocess p\n  command: p\n"
                         "  add_message_definition_dir: pmd\n",
    })
    assert config.message_definition_dirs == [str(tmp_path / "md"), str(tmp_path / "inc/md2")]
    assert config.processes["p"].message_definition_dirs == [str(tmp_path / "inc/pmd")]


def test_requires_version_accepts_older(tmp_path: Path) -> None:
    config = load_files(tmp_path, {"main.lnc": "requires_version 0.0.9\n" + HEAD})
    assert config.instance.name == "demo"


def test_parse_text_accepts_str_and_bytes() -> None:
    for text in (HEAD, HEAD.encode()):
        config = parse_text(text, "/no/such/dir/x.lnc")
        assert config.files == ["/no/such/dir/x.lnc"]
        assert config.instance.location.file == "/no/such/dir/x.lnc"


def test_relative_main_path(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    write(tmp_path, {"cfg/main.lnc": HEAD + "include inc.lnc\n", "cfg/inc.lnc": "# empty\n"})
    monkeypatch.chdir(tmp_path)
    config = load("cfg/main.lnc")
    assert config.files == ["cfg/main.lnc", os.path.join("cfg", "inc.lnc")]
