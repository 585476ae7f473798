"""The modules the command-line entry points load (docs/manager.md, "Start-up time of the
command line"): `--help` of ln_manager, ln_generate and ln_record, and `ln_manager
status|topics|services` against a running manager, each run in a fresh interpreter, must not
load numpy, asyncio, ctypes (libln), ln_generate, the registry, the manager's composition
root or the web UI's server; `--help` not even the client codec.  What is asserted is the
import set, never a time."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from mgrproc import Manager

# loaded by none of the entry points' light paths
HEAVY = ("numpy", "asyncio", "ctypes", "links_and_nodes._libln", "links_and_nodes._clientlib",
         "links_and_nodes._client", "links_and_nodes.md_loader",
         "links_and_nodes.manager.registry.core", "links_and_nodes.manager.registry.server",
         "links_and_nodes.manager.registry.model", "links_and_nodes.manager.registry.segments",
         "links_and_nodes.manager.app", "links_and_nodes.manager.config",
         "links_and_nodes.manager.frontends.webui.server",
         "links_and_nodes.tools.introspection.client",
         "links_and_nodes.tools.introspection.commands", "links_and_nodes.mcap_format",
         "links_and_nodes.record.recorder")
# what --help does not need either: the manager's client and its wire codec, the md parser
NOT_FOR_HELP = HEAVY + ("links_and_nodes.tools.scripting", "links_and_nodes.tools.protocol",
                        "links_and_nodes.wire.schema")

RUN = """
import json, sys
sys.argv = [{prog!r}, *{args!r}]
from {module} import main
try:
    status = main()
except SystemExit as exc:
    status = exc.code
sys.stdout.flush()
with open({out!r}, "w") as f:
    json.dump({{"status": status, "modules": sorted(sys.modules)}}, f)
"""


def loaded(tmp_path: Path, module: str, prog: str, *args: str) -> tuple[int, set[str], str]:
    """Exit status, the modules loaded and stdout of `prog args` (its main() in `module`)
    in a new interpreter."""
    out = tmp_path / f"{prog}-{'-'.join(args) or 'none'}.json"
    env = {k: v for k, v in os.environ.items() if k != "LN_MANAGER"}
    done = subprocess.run([sys.executable, "-c", RUN.format(prog=prog, args=list(args),
                                                            module=module, out=str(out))],
                          capture_output=True, text=True, env=env, timeout=60)
    assert done.returncode == 0, done.stderr
    result = json.loads(out.read_text())
    return result["status"], set(result["modules"]), done.stdout


def offending(modules: set[str], forbidden: tuple[str, ...]) -> list[str]:
    return sorted(m for m in modules
                  if any(m == f or m.startswith(f + ".") for f in forbidden))


@pytest.mark.parametrize(("module", "prog", "forbidden"), [
    ("links_and_nodes.manager.frontends.cli", "ln_manager", NOT_FOR_HELP + ("ln_generate",)),
    ("ln_generate.cli", "ln_generate", NOT_FOR_HELP + ("links_and_nodes",)),
    ("links_and_nodes.record.record_cli", "ln_record", NOT_FOR_HELP + ("ln_generate",)),
])
def test_help_loads_only_the_parser(tmp_path: Path, module: str, prog: str,
                                    forbidden: tuple[str, ...]) -> None:
    status, modules, stdout = loaded(tmp_path, module, prog, "--help")
    assert status == 0
    assert stdout.startswith(f"usage: {prog}")
    assert offending(modules, forbidden) == []


def test_manager_help_still_lists_the_table(tmp_path: Path) -> None:
    """The light path reads the same command table: every subcommand is in the help."""
    from links_and_nodes.manager.frontends import remote_cli

    _, _, stdout = loaded(tmp_path, "links_and_nodes.manager.frontends.cli", "ln_manager",
                          "--help")
    listed = " ".join(stdout.split())
    assert ", ".join(remote_cli.names()) in listed


@pytest.mark.parametrize("command", ["status", "topics", "services"])
def test_remote_command_loads_only_the_client(tmp_path: Path, manager: Manager,
                                              command: str) -> None:
    status, modules, stdout = loaded(tmp_path, "links_and_nodes.manager.frontends.cli",
                                     "ln_manager", command, "--json", "--manager",
                                     f"127.0.0.1:{manager.port}")
    assert status == 0
    json.loads(stdout)  # the manager's answer
    assert "links_and_nodes.tools.protocol" in modules  # it did talk to the manager
    assert offending(modules, HEAVY + ("ln_generate",)) == []


EAGER = """
import json
from links_and_nodes.manager.frontends.webui import auth
from links_and_nodes.tools import protocol as p
made, hashed = sorted(p._made), auth._dummy.cache_info().currsize
hello = p.Hello
same = hello is p.message_class(p.MsgType.HELLO) is p.MESSAGES[p.MsgType.HELLO]
auth.Sessions({"user": auth.hash_password("pw", n=2)})
print(json.dumps({"made": made, "hashed": hashed, "same": same,
                  "hashed_for_sessions": auth._dummy.cache_info().currsize}))
"""


def test_launch_modules_build_nothing_at_import() -> None:
    """`ln_manager -c` imports the client codec and the web UI's auth module: importing them
    makes no message class and computes no scrypt hash (each costs milliseconds at every
    start); a class is made when first used, the same one however it is reached, and the hash
    unknown users are checked against when the first Sessions with users is made."""
    done = subprocess.run([sys.executable, "-c", EAGER], capture_output=True, text=True,
                          timeout=60)
    assert done.returncode == 0, done.stderr
    result = json.loads(done.stdout)
    assert result == {"made": [], "hashed": 0, "same": True, "hashed_for_sessions": 1}
