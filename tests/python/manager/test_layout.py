"""The manager package's layout: every module imports on its own in a fresh interpreter (an
import cycle that works only in one import order fails here), and imports go one way,
frontends -> processes/network/loggers/parameters/introspection -> registry -> config,
with only the composition root (app.py, runner.py, the package's __init__/__main__)
reaching into frontends/ from outside it."""

from __future__ import annotations

import ast
import os
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[3]
PACKAGE = REPO / "python" / "links_and_nodes" / "manager"
ROOT = "links_and_nodes.manager"

# layer of each top-level part: a module may import its own layer and lower ones only
LAYERS = {"config": 0, "registry": 1, "processes": 2, "network": 2, "loggers": 2,
          "parameters": 2, "introspection": 2, "frontends": 3}
COMPOSITION_ROOT = {"app", "runner", "__init__", "__main__"}
CALLS_THE_ROOT = {("frontends.cli", "app")}  # `ln_manager` parses its arguments, calls app

# Imports against the direction that are known and not yet fixed, as (importing module,
# imported part); a new pair fails the test, and so does one that is gone.
# - The feature packages register their console/CLI commands in the command table
#   (frontends/commands), raise frontends.control.ControlError and use the scripting
#   client's Manager/ManagerError: the fix is moving the table, ControlError and
#   ManagerError below the feature packages.
# - config checks parameter values with parameters.tools.parse_value (when a process's
#   `parameters` key is read): the fix is moving that rule below config/.
KNOWN = {
    ("config.process_params", "parameters"),
    ("introspection.api", "frontends"), ("introspection.args", "frontends"),
    ("introspection.cli", "frontends"), ("introspection.console", "frontends"),
    ("introspection.control", "frontends"),
    ("loggers.commands", "frontends"), ("loggers.views", "frontends"),
    ("parameters.api", "frontends"), ("parameters.cli", "frontends"),
    ("parameters.commands", "frontends"), ("parameters.console", "frontends"),
}


def _modules() -> list[str]:
    names = []
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = list(path.relative_to(PACKAGE).with_suffix("").parts)
        if parts[-1] == "__init__" and len(parts) > 1:
            parts.pop()
        names.append(".".join(parts))
    return names


MODULES = _modules()
RUN_ON_IMPORT = {"__main__"}  # runs ln_manager when imported


def _path(module: str) -> Path:
    if module in ("__init__", "__main__"):
        return PACKAGE / f"{module}.py"
    path = PACKAGE.joinpath(*module.split("."))
    return path / "__init__.py" if path.is_dir() else path.with_suffix(".py")


def _imported(module: str, top_level: bool = False) -> set[str]:
    """The modules of the manager package `module` imports, anywhere in it (also inside
    functions), relative to the package ("registry.core"); with `top_level` only those
    imported when it is (not in functions, not for type checking only)."""
    path = _path(module)
    package = module.split(".") if path.name == "__init__.py" or module == "__init__" \
        else module.split(".")[:-1]
    if module == "__init__":
        package = []
    found = set()
    tree = ast.parse(path.read_text(), str(path))
    nodes = ast.walk(tree) if not top_level else (
        n for stmt in tree.body if not (isinstance(stmt, ast.If)
                                        and "TYPE_CHECKING" in ast.unparse(stmt.test))
        for n in ast.walk(stmt)
        if not isinstance(stmt, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef))
    for node in nodes:
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = [ROOT, *package][:len(package) + 2 - node.level]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            names = [target] + [f"{target}.{alias.name}" for alias in node.names]
        elif isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        else:
            continue
        found |= {n[len(ROOT) + 1:] for n in names if n.startswith(ROOT + ".")}
    return {name for name in found if name in MODULES}  # a module, not a name in one


def test_the_package_has_its_parts() -> None:
    assert {m.split(".")[0] for m in MODULES} >= set(LAYERS) | {"app"}


@pytest.mark.parametrize("module", [m for m in MODULES if m not in RUN_ON_IMPORT])
def test_module_imports_alone(module: str) -> None:
    name = ROOT if module == "__init__" else f"{ROOT}.{module}"
    path = [str(REPO / "python"), *filter(None, [os.environ.get("PYTHONPATH")])]
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(path))
    run = subprocess.run([sys.executable, "-c", f"import {name}"], env=env,
                         capture_output=True, text=True, timeout=60)
    assert run.returncode == 0, run.stderr


def test_imports_go_one_way() -> None:
    against = set()
    for module in MODULES:
        part = module.split(".")[0]
        if part in COMPOSITION_ROOT:
            continue
        for target in _imported(module):
            to = target.split(".")[0]
            if to in COMPOSITION_ROOT and (module, to) not in CALLS_THE_ROOT \
                    or LAYERS.get(to, 0) > LAYERS[part]:
                against.add((module, to))
    assert against - KNOWN == set(), "imports against the layers"
    assert KNOWN - against == set(), "fixed: take them off KNOWN"


def test_no_module_imports_itself_through_others() -> None:
    """No cycle of imports run at import time (those inside functions or for type
    checking only do not count): each would work in one import order only."""
    edges = {module: {t for t in _imported(module, top_level=True)
                      if not (module + ".").startswith(t + ".")}  # itself, its packages
             for module in MODULES}
    done: set[str] = set()

    def visit(module: str, path: list[str]) -> None:
        if module in path:
            cycle = path[path.index(module):] + [module]
            raise AssertionError("import cycle: " + " -> ".join(cycle))
        if module in done:
            return
        for target in sorted(edges[module]):
            visit(target, [*path, module])
        done.add(module)

    for module in MODULES:
        visit(module, [])
