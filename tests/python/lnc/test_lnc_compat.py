"""What files written for the original Links and Nodes need: the conditional functions,
`%(shell)`, `undef`, `append environment`, `pipe_include`, `requires_version` against the
language version, warnings where the original was lenient and `strict`, `stack_size`;
exact values and exact `file:line:col` messages."""

from __future__ import annotations

import os
import time
from pathlib import Path

import pytest

from links_and_nodes.manager.config import LANGUAGE_VERSION, ConfigError, load
from links_and_nodes.manager.config.model import ResourceLimit

from .helpers import cfg, load_files, write


def defines_of(tmp_path: Path, body: str, **kw: object) -> dict[str, str]:
    return load_files(tmp_path, {"main.lnc": cfg(body)}, **kw).defines


def problems(tmp_path: Path, files: dict[str, str], **kw: object) -> list[str]:
    with pytest.raises(ConfigError) as err:
        load(write(tmp_path, files), env=kw.pop("env", {}), **kw)  # type: ignore[arg-type]
    return str(err.value).split("\n")


# ---------------------------------------------------------------- conditional functions

def test_ifndef_ifdef_ifeq(tmp_path: Path) -> None:
    d = defines_of(tmp_path, """
        defines
        given: yes
        a: %(ifndef "given", "default")
        b: %(ifndef "missing", "default")
        c: %(ifdef "given", "then", "else")
        e: %(ifdef "missing", "then", "else")
        f: %(ifdef "missing", "then")
        g: %(ifeq "%(given)", "yes", "same", "different")
        h: %(ifeq "x", "y", "same", "different")
        i: %(ifeq "x", "y", "same")
        j: %(ifndef "rk_base", "%(dirname %(dirname /a/b/c))")
        """)
    assert {k: d[k] for k in "abcefghij"} == {
        "a": "yes", "b": "default", "c": "then", "e": "else", "f": "", "g": "same",
        "h": "different", "i": "", "j": "/a"}


def test_ifexists_relative_to_the_file(tmp_path: Path) -> None:
    (tmp_path / "bin").mkdir()
    (tmp_path / "bin" / "robotkernel").write_text("")
    d = defines_of(tmp_path, """
        defines
        base: %(CURDIR)
        here: %(ifexists "%(base)/bin/robotkernel", "local_install", "rmpm_release")
        rel: %(ifexists "bin/robotkernel", "yes", "no")
        gone: %(ifexists "bin/nothing", "yes", "no")
        """)
    assert (d["here"], d["rel"], d["gone"]) == ("local_install", "yes", "no")


def test_nested_quoted_conditionals(tmp_path: Path) -> None:
    """robotkernel_gui.inc.lnc nests quoted calls inside quoted arguments."""
    (tmp_path / "bin").mkdir()
    (tmp_path / "bin" / "gui").write_text("")
    d = defines_of(tmp_path, """
        defines
        p: %(CURDIR)
        t: %(ifexists "%(p)/gui", "path_to_bin", "%(ifexists "%(p)/bin/gui", "local_install", "rmpm_release")")
        b: %(ifeq "%(t)", "path_to_bin", "%(p)/gui", "%(ifeq "%(t)", "local_install", "%(p)/bin/gui", "%(p)/bin/$(ARCH)/gui")")
        """)
    assert d["t"] == "local_install"
    assert d["b"] == f"{tmp_path}/bin/gui"


def test_functions_in_section_headers_and_use_template(tmp_path: Path) -> None:
    config = load_files(tmp_path, {"main.lnc": cfg("""
        template base(cmd)
        command: %(cmd) --run
        defines
        tpl: base("robot")
        process %(ifndef "rk_name", "robotkernel")
        use_template: %(tpl)
        """)})
    assert list(config.processes) == ["robotkernel"]
    assert config.processes["robotkernel"].command == "robot --run"


def test_branch_not_taken_is_not_evaluated(tmp_path: Path) -> None:
    """An unknown name in the branch not taken is a warning at its place; a command in it
    does not run."""
    marker = tmp_path / "ran"
    config = load_files(tmp_path, {"main.lnc": cfg(f"""
        defines
        x: yes
        a: %(ifdef "x", "fine", "%(nowhere)")
        b: %(ifeq "1", "2", "%(shell "touch {marker}")", "kept")
        """)})
    assert (config.defines["a"], config.defines["b"]) == ("fine", "kept")
    assert not marker.exists()
    main = tmp_path / "main.lnc"
    assert [str(w) for w in config.warnings] == [
        f"{main}:6:26: unknown name 'nowhere' in '%()' (in a branch that is not taken)"]


def test_unknown_name_in_the_taken_branch_is_an_error(tmp_path: Path) -> None:
    main = tmp_path / "main.lnc"
    assert problems(tmp_path, {"main.lnc": cfg("""
        defines
        a: %(ifdef "x", "fine", "%(nowhere)")
        """)}) == [f"{main}:5:26: unknown name 'nowhere' in '%()'"]


def test_conditional_arity_errors(tmp_path: Path) -> None:
    main = tmp_path / "main.lnc"
    assert problems(tmp_path, {"main.lnc": cfg("""
        defines
        a: %(ifndef "x")
        b: %(ifeq "a", "b")
        c: %(ifexists "p", "a", "b", "c")
        """)}) == [
        f"{main}:5:4: 'ifndef' takes \"NAME\", \"DEFAULT\", got 1 argument",
        f"{main}:6:4: 'ifeq' takes \"A\", \"B\", \"THEN\" or \"A\", \"B\", \"THEN\", \"ELSE\", "
        "got 2 arguments",
        f"{main}:7:4: 'ifexists' takes \"PATH\", \"THEN\" or \"PATH\", \"THEN\", \"ELSE\", "
        "got 4 arguments"]


def test_basename(tmp_path: Path) -> None:
    assert defines_of(tmp_path, "defines\nb: %(basename /opt/rk/2.1)\n")["b"] == "2.1"


# ---------------------------------------------------------------- shell

def test_shell_output_without_trailing_newlines(tmp_path: Path) -> None:
    d = defines_of(tmp_path, """
        defines
        a: %(shell "printf 'two\\nlines\\n\\n'")
        b: %(shell echo $LN_TEST_VALUE)
        c: %(shell "pwd")
        """, env={"LN_TEST_VALUE": "from env", "PATH": os.environ["PATH"]})
    assert d["a"] == "two\nlines"
    assert d["b"] == "from env"
    assert d["c"] == str(tmp_path)


def test_failing_shell_command(tmp_path: Path) -> None:
    main = tmp_path / "main.lnc"
    assert problems(tmp_path, {"main.lnc": cfg("""
        defines
        a: %(shell "echo oops >&2; exit 3")
        """)}, env={"PATH": os.environ["PATH"]}) == [
        f"{main}:5:4: command 'echo oops >&2; exit 3' failed with exit status 3: oops"]


def test_hanging_shell_command_is_killed(tmp_path: Path) -> None:
    main = tmp_path / "main.lnc"
    start = time.monotonic()
    assert problems(tmp_path, {"main.lnc": cfg("""
        defines
        a: %(shell "sleep 30 & sleep 30")
        """)}, env={"PATH": os.environ["PATH"]}, shell_timeout=0.3) == [
        f"{main}:5:4: command 'sleep 30 & sleep 30' did not finish within 0.3 s (killed)"]
    assert time.monotonic() - start < 25  # the background sleep held stdout: killed too


# ---------------------------------------------------------------- undef, append, pipe_include

def test_undef_removes_defines(tmp_path: Path) -> None:
    config = load_files(tmp_path, {"main.lnc": cfg("""
        defines
        a: 1
        b: 2
        c: 3
        undef: a
        undef: b, never_defined
        process p
        ifdef a: command: wrong
        ifndef a: command: right %(c)
        """)}, defines={"c": "fixed"})
    assert "a" not in config.defines and "b" not in config.defines
    assert "undef" not in config.defines
    assert config.processes["p"].command == "right fixed"


def test_undef_of_a_caller_define_keeps_it(tmp_path: Path) -> None:
    d = defines_of(tmp_path, "defines\nundef: c\n", defines={"c": "fixed"})
    assert d["c"] == "fixed"


def test_append_environment(tmp_path: Path) -> None:
    config = load_files(tmp_path, {"main.lnc": cfg("""
        defines
        mods: /opt/a
        process p
        command: p
        append environment ROBOTKERNEL_MODULE_PATH: %(mods)
        append environment ROBOTKERNEL_MODULE_PATH: /opt/b
        ifdef mods: append environment OTHER: x
        add environment: THIRD=3
        """)})
    assert config.processes["p"].environment == {
        "ROBOTKERNEL_MODULE_PATH": "/opt/a:/opt/b", "OTHER": "x", "THIRD": "3"}


def test_append_environment_outside_a_process(tmp_path: Path) -> None:
    main = tmp_path / "main.lnc"
    assert problems(tmp_path, {"main.lnc": cfg("""
        defines
        append environment X: y
        """)}) == [f"{main}:5:1: 'append environment' outside of a process section"]


def test_pipe_include(tmp_path: Path) -> None:
    (tmp_path / "gen.sh").write_text(
        "echo 'process generated'\necho '    command: run %(CURDIR)'\n"
        "echo 'include part.inc.lnc'\n")
    (tmp_path / "part.inc.lnc").write_text("process part\ncommand: part\n")
    config = load_files(tmp_path, {"main.lnc": cfg("""
        pipe_include sh gen.sh
        """)}, env={"PATH": os.environ["PATH"]})
    assert list(config.processes) == ["generated", "part"]
    assert config.processes["generated"].command == f"run {tmp_path}"


def test_pipe_include_errors_point_at_the_directive(tmp_path: Path) -> None:
    (tmp_path / "gen.sh").write_text("echo 'process g'\necho 'command: x'\necho 'bogus: 1'\n")
    main = tmp_path / "main.lnc"
    assert problems(tmp_path, {"main.lnc": cfg("""
        pipe_include sh gen.sh
        pipe_include "exit 4"
        pipe_include sleep 30
        """)}, env={"PATH": os.environ["PATH"]}, shell_timeout=0.3) == [
        f"{main}:5:15: command 'exit 4' failed with exit status 4",
        f"{main}:6:14: command 'sleep 30' did not finish within 0.3 s (killed)",
        f"{main}:4:1: output of pipe_include:3:1: unknown key 'bogus' in process 'g'",
    ]


# ---------------------------------------------------------------- version, warnings, strict

def test_requires_version_is_the_language_version(tmp_path: Path) -> None:
    load_files(tmp_path, {"main.lnc": cfg(f"""
        requires_version 0.2.43
        requires_version 2
        requires_version {LANGUAGE_VERSION}
        """)})
    main = tmp_path / "main.lnc"
    assert problems(tmp_path, {"main.lnc": cfg("requires_version 2.99.1\n")}) == [
        f"{main}:4:18: this file requires version 2.99.1 of the Links and Nodes "
        f"configuration language; links_and_nodes reads version {LANGUAGE_VERSION}"]


def test_missing_md_dir_is_a_warning_and_strict_makes_it_an_error(tmp_path: Path) -> None:
    files = {"main.lnc": cfg("""
        add_message_definition_dir: no/such/dir
        process p
        command: p
        add_message_definition_dir: %(CURDIR)/gone
        """)}
    main = tmp_path / "main.lnc"
    config = load_files(tmp_path, files)
    assert [str(w) for w in config.warnings] == [
        f"{main}:4:29: message definition directory 'no/such/dir' not found (ignored)",
        f"{main}:7:29: message definition directory '{tmp_path}/gone' not found (ignored)"]
    assert config.message_definition_dirs == []
    assert problems(tmp_path, files, strict=True) == [
        f"{w} [warning, an error with --strict]" for w in config.warnings]


def test_empty_define_in_a_recursive_glob(tmp_path: Path) -> None:
    main = tmp_path / "main.lnc"
    assert problems(tmp_path, {"main.lnc": cfg("""
        defines
        gen:
        include_glob %(gen)/**/*.lnc
        """)}) == [f"{main}:6:14: '/**/*.lnc' would search the whole file system "
                   "(is a define in it empty?)"]


def test_stack_size(tmp_path: Path) -> None:
    config = load_files(tmp_path, {"main.lnc": cfg("""
        process p
        command: p
        set_resource_limits: nofile:64, stack:1M
        stack_size: 8M
        """)})
    assert config.processes["p"].resource_limits == [
        ResourceLimit("nofile", 64, 64), ResourceLimit("stack", 8 << 20, 8 << 20)]
