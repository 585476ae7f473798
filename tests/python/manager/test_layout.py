"""The manager package's layout: every module imports on its own in a fresh interpreter (an
import cycle that works only in one import order fails here), and imports go one way,
frontends -> processes/network/loggers/parameters/introspection -> registry -> config,
with only the composition root (app.py, runner.py, the package's __init__/__main__)
reaching into frontends/ from outside it.  Below them all is links_and_nodes/tools/ (the
command table the features register into, the clients' side of the protocol, scripting,
introspection and parameters): it and every other part outside manager/ are clients and
import none of the manager's insides, only its public `links_and_nodes.manager.connect`."""

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
KNOWN: set[tuple[str, str]] = set()

PACKAGES = REPO / "python" / "links_and_nodes"
TOOLS = PACKAGES / "tools"
PUBLIC = {"connect", "Manager", "ManagerError"}  # links_and_nodes.manager's public names


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


def _absolute_imports(path: Path) -> set[tuple[str, str]]:
    """(module, name) of every import in the file at `path` (anywhere in it), relative
    imports resolved; name is "" for `import module`."""
    parts = list(path.relative_to(PACKAGES.parent).with_suffix("").parts)
    package = parts if parts[-1] == "__init__" else parts[:-1]
    package = [p for p in package if p != "__init__"]
    found = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.ImportFrom):
            base = package[:len(package) + 1 - node.level] if node.level else []
            module = ".".join(base + ([node.module] if node.module else []))
            found |= {(module, alias.name) for alias in node.names}
        elif isinstance(node, ast.Import):
            found |= {(alias.name, "") for alias in node.names}
    return found


def _outside_manager() -> list[Path]:
    return [path for path in sorted(PACKAGES.rglob("*.py"))
            if PACKAGE not in path.parents and "__pycache__" not in path.parts]


def test_clients_import_no_manager_insides() -> None:
    """The bridges, ln_record/ln_play, tools/ and everything else outside manager/ are
    ordinary clients: of the manager they may import its public connect() only."""
    wrong = set()
    for path in _outside_manager():
        for module, name in _absolute_imports(path):
            if module == ROOT and (name in PUBLIC or name == ""):
                continue
            if module == ROOT or module.startswith(ROOT + ".") \
                    or (module == "links_and_nodes" and name == "manager"):
                wrong.add((str(path.relative_to(PACKAGES)), f"{module} {name}".strip()))
    assert wrong == set(), "modules outside manager/ importing the manager's insides"


def test_the_command_table_is_a_leaf() -> None:
    """tools/commands/ imports nothing of ours outside itself (the features it lists are
    imported by name when the table is first read)."""
    table = TOOLS / "commands"
    wrong = {(path.name, module) for path in sorted(table.glob("*.py"))
             for module, _name in _absolute_imports(path)
             if module.startswith("links_and_nodes")
             and not module.startswith("links_and_nodes.tools.commands")}
    assert wrong == set()


@pytest.mark.parametrize("path", sorted(str(p.relative_to(TOOLS)) for p in TOOLS.rglob("*.py")
                                        if "__pycache__" not in p.parts))
def test_tools_module_imports_alone(path: str) -> None:
    parts = list(Path(path).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    name = ".".join(["links_and_nodes.tools", *parts])
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [str(REPO / "python"), *filter(None, [os.environ.get("PYTHONPATH")])]))
    run = subprocess.run([sys.executable, "-c", f"import {name}"], env=env,
                         capture_output=True, text=True, timeout=60)
    assert run.returncode == 0, run.stderr
