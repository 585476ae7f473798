"""How tests/python/conftest.py marks a test: from what its code reaches, the test function,
the fixtures it uses and the test code they call (files under tests/), followed into the
product's modules (python/links_and_nodes), which are judged by their source and by what they
import, transitively: whether it starts a process (`integration`) and whether it loads the
project's native code into the interpreter (`native`).  tests/README.md, "Markers"."""

from __future__ import annotations

import ctypes
import dis
import importlib
import importlib.util
import inspect
import os
import re
import sys
import types
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

REPO = Path(__file__).resolve().parents[2]
TESTS = str(REPO / "tests") + os.sep
PRODUCT = str(REPO / "python" / "links_and_nodes") + os.sep
# Names that start a process, by the module they are reached through; a module in
# SPAWN_MODULES starts processes whatever is used of it (but its exceptions).
SPAWN_ATTRS = {
    "subprocess": {"Popen", "run", "call", "check_call", "check_output", "getoutput",
                   "getstatusoutput"},
    "os": {"fork", "forkpty", "posix_spawn", "posix_spawnp", "system", "popen", "execv",
           "execve", "execvp", "execvpe", "execl", "execle", "execlp", "execlpe", "spawnv",
           "spawnve", "spawnvp", "spawnvpe", "spawnl", "spawnle", "spawnlp", "spawnlpe"},
    "asyncio": {"create_subprocess_exec", "create_subprocess_shell"},
    "pty": {"fork", "spawn"},
    "cffi": {"compile", "verify"},  # FFI().compile() runs the C compiler
}
# (pytest_lsp: its client starts the language server under test)
SPAWN_MODULES = ("multiprocessing", "concurrent.futures.process", "pexpect", "pytest_lsp")
# An event loop's own methods, whatever object they are called on.
SPAWN_METHODS = {"subprocess_exec", "subprocess_shell", "create_subprocess_exec",
                 "create_subprocess_shell"}
# Product modules that start a process only when their input asks for it: what, in the source
# of a test or of the test code it reaches, asks for it.  (lnc's %(shell ...) and
# pipe_include run a shell; a test that parses plain lnc starts nothing; a test that loads
# the real configurations of ../shared/real_ln, some of which use both, may
# start one.)  A module renamed and not listed here only makes more tests integration tests.
_LNC_SHELL = re.compile(r"%\(shell\b|\bpipe_include\b|\breal_ln\b")
SPAWN_ON_INPUT = {
    "links_and_nodes.manager.config.shell": _LNC_SHELL,
}


def _code_objects(code: types.CodeType) -> Iterator[types.CodeType]:
    yield code
    for const in code.co_consts:
        if isinstance(const, types.CodeType):
            yield from _code_objects(const)


def _source_text(obj: Any) -> str:
    try:
        return inspect.getsource(obj)
    except (OSError, TypeError):
        return ""


def _source_file(obj: Any) -> str:
    module = sys.modules.get(getattr(obj, "__module__", None) or "")
    return getattr(module, "__file__", None) or ""


class _Reach:
    """What a function reaches through the names its code uses, followed through the test
    code (files under tests/) and judged at the product's modules (python/links_and_nodes)
    by their source: whether they start processes or load native code, with what they
    import, transitively.  Each function, class or module is a node with what it does itself
    and the nodes it uses; a test is judged by all nodes it reaches (cycles included)."""

    def __init__(self) -> None:
        self.nodes: dict[Any, tuple[bool, bool, list[Any]]] = {}
        self.results: dict[Any, tuple[bool, bool]] = {}

    def of(self, func: Any) -> tuple[bool, bool]:
        """(starts a process, loads native code) for a function, method or class."""
        start = self._key(func)
        if start in self.results:
            return self.results[start]
        spawn = native = False
        seen, todo = {start}, [start]
        on_input: set[str] = set()
        while todo and not (spawn and native):
            key = todo.pop()
            s, n, edges = self._node(key)
            spawn, native = spawn or s, native or n
            if isinstance(key, str) and key in SPAWN_ON_INPUT:
                on_input.add(key)
            for edge in edges:
                if edge not in seen:
                    seen.add(edge)
                    todo.append(edge)
        if on_input and not spawn:
            # the whole test module: what asks may sit in a constant (a corpus's path)
            texts = [_source_text(inspect.getmodule(key) or key)
                     for key in seen if not isinstance(key, str)]
            spawn = any(SPAWN_ON_INPUT[name].search(text)
                        for name in on_input for text in texts)
        self.results[start] = (spawn, native)
        return spawn, native

    @staticmethod
    def _key(obj: Any) -> Any:
        if isinstance(obj, str):  # a product module by name
            return obj
        inner = getattr(getattr(obj, "hypothesis", None), "inner_test", None)
        obj = inner or obj
        return inspect.unwrap(obj) if inspect.isfunction(obj) else obj

    def _node(self, key: Any) -> tuple[bool, bool, list[Any]]:
        if key not in self.nodes:
            if isinstance(key, str):
                self.nodes[key] = self._product(key)
            else:
                spawn, native, edges = False, False, []
                for part in self._parts(key):
                    s, n, e = self._function(part)
                    spawn, native = spawn or s, native or n
                    edges += e
                self.nodes[key] = (spawn, native, edges)
        return self.nodes[key]

    @staticmethod
    def _parts(obj: Any) -> Iterator[types.FunctionType]:
        if inspect.isclass(obj):
            for klass in obj.__mro__:
                if not _source_file(klass).startswith(TESTS):
                    continue
                for value in vars(klass).values():
                    value = getattr(value, "__func__", value)  # static- and classmethods
                    if isinstance(value, property):
                        yield from (f for f in (value.fget, value.fset) if f)
                    elif inspect.isfunction(value):
                        yield value
        elif inspect.isfunction(obj):
            yield obj

    def _function(self, func: types.FunctionType) -> tuple[bool, bool, list[Any]]:
        names: set[str] = set()
        imported: list[str] = []
        for code in _code_objects(func.__code__):
            names.update(code.co_names)
            imported += [i.argval for i in dis.get_instructions(code)
                         if i.opname == "IMPORT_NAME"]
        spawn, native, edges = bool(names & SPAWN_METHODS), False, []
        namespace = dict(func.__globals__)
        for name, cell in zip(func.__code__.co_freevars, func.__closure__ or (), strict=True):
            try:
                namespace[name] = cell.cell_contents
            except ValueError:  # an empty cell
                pass
        values = [namespace[name] for name in names | set(func.__code__.co_freevars)
                  if name in namespace]
        for module_name in imported:  # imports inside the function
            if module_name.partition(".")[0] == "links_and_nodes":
                edges.append(module_name)  # judged from its source: no import
                continue
            module = sys.modules.get(module_name)
            if module is None and _is_test_module(module_name):
                try:
                    module = importlib.import_module(module_name)
                except pytest.skip.Exception:  # it skips itself here (a corpus not beside)
                    module = None
            if module is not None:
                values.append(module)
        for value in values:
            s, n, e = self._value(value, names)
            spawn, native = spawn or s, native or n
            edges += e
        return spawn, native, edges

    def _value(self, value: Any, names: set[str]) -> tuple[bool, bool, list[Any]]:
        if isinstance(value, types.ModuleType):
            return self._module(value, names)
        if isinstance(value, (ctypes.CDLL, ctypes._CFuncPtr)):
            return False, True, []
        module = getattr(value, "__module__", None) or ""
        if module.startswith(SPAWN_MODULES):
            return True, False, []
        for prefix, attrs in SPAWN_ATTRS.items():
            if module == prefix or module.startswith(prefix + "."):
                return (getattr(value, "__name__", "") in attrs or bool(names & attrs)
                        if inspect.isclass(value) else getattr(value, "__name__", "") in attrs,
                        False, [])
        if not (inspect.isfunction(value) or inspect.isclass(value)):
            return False, False, []
        path = _source_file(value)
        if path.startswith(TESTS):
            return False, False, [self._key(value)]
        if path.startswith(PRODUCT):
            return False, False, [module]
        return False, False, []

    def _module(self, module: types.ModuleType, names: set[str]) -> tuple[bool, bool, list[Any]]:
        name = module.__name__
        if name.startswith(SPAWN_MODULES):
            return True, False, []
        for prefix, attrs in SPAWN_ATTRS.items():
            if name == prefix or name.startswith(prefix + "."):
                return bool(names & attrs), False, []
        path = getattr(module, "__file__", None) or ""
        if path.startswith(TESTS):  # module.function(): follow what of it is used
            edges = []
            for attr in names:
                value = inspect.getattr_static(module, attr, None)
                if value is not None and not isinstance(value, types.ModuleType):
                    s, n, e = self._value(value, names)
                    if s or n:
                        return s, n, []
                    edges += e
            return False, False, edges
        if path.startswith(PRODUCT):
            return False, False, [name]
        return False, False, []

    @staticmethod
    def _product(name: str) -> tuple[bool, bool, list[Any]]:
        """What a product module's source does itself, and the product modules it imports
        anywhere in it (at top level or in a function)."""
        path = _product_file(name)
        if path is None:
            return False, False, []
        text = path.read_text()
        spawn = name not in SPAWN_ON_INPUT and bool(re.search(
            r"\b(subprocess|create_subprocess_\w+|os\.(fork|posix_spawnp?|system|exec\w+)|"
            r"multiprocessing)\b", text))
        native = bool(re.search(r"\bctypes\.CDLL\b|\b_native\b", text))
        return spawn, native, list(_imports(name, text))


def _is_test_module(name: str) -> bool:
    """Whether `name` is a module of the tests (imported here without harm)."""
    try:
        spec = importlib.util.find_spec(name)
    except (ImportError, ValueError):
        return False
    return bool(spec and spec.origin and spec.origin.startswith(TESTS))


def _product_file(name: str) -> Path | None:
    """The source of product module `name`, found without importing it (importing
    links_and_nodes._libln would load libln)."""
    base = REPO / "python" / Path(*name.split("."))
    for path in (base.with_suffix(".py"), base / "__init__.py"):
        if path.is_file():
            return path
    return None


def _imports(name: str, text: str) -> Iterator[str]:
    """The product modules `text` (of module `name`) imports, at top level or in a function."""
    is_package = (_product_file(name) or Path()).name == "__init__.py"
    package = name if is_package else name.rpartition(".")[0]
    for match in re.finditer(r"^[ \t]*(?:from[ \t]+(\.*)([\w.]*)[ \t]+import[ \t]+"
                             r"(?:\(([^)]*)\)|([\w \t,]+))|import[ \t]+(links_and_nodes[\w.]*))",
                             text, re.M):
        dots, base, listed, what, plain = match.groups()
        what = listed or what
        if plain:
            candidates = [plain]
        else:
            if dots:
                parent = package.rsplit(".", len(dots) - 1)[0] if len(dots) > 1 else package
                base = f"{parent}.{base}" if base else parent
            if not base.startswith("links_and_nodes"):
                continue
            # from X import y: the module X.y, or else X, whose attribute y is
            words = (w.split()[0] for w in what.split(",") if w.split())
            candidates = [f"{base}.{w}" if _product_file(f"{base}.{w}") else base
                          for w in words]
        yield from (c for c in candidates if _product_file(c))


_REACH = _Reach()


def marks_of(item: pytest.Function) -> tuple[bool, bool]:
    """(integration, native) of a test: of its function and of every fixture it uses."""
    spawn, native = _REACH.of(item.function)
    info = getattr(item, "_fixtureinfo", None)
    for defs in (info.name2fixturedefs.values() if info else ()):
        for fixturedef in defs:
            s, n = _REACH.of(fixturedef.func)
            spawn, native = spawn or s, native or n
    return spawn, native
