"""The packaging metadata agrees with the code: one version in ln.h, the Python package and
debian/changelog; pyproject.toml installs every folder of message_definitions/; every
console script is installed alike by pip, SCons and the Debian package, with a manual page
and a place in the installed-system test; and debian/libln1.symbols lists exactly what
libln exports (needs the built library; skipped without it only outside CI, where it must
fail)."""

import os
import re
import subprocess
import tomllib
from pathlib import Path

import pytest

import links_and_nodes

REPO = Path(__file__).resolve().parents[3]
LIBLN = REPO / "build" / "release" / "libln" / "libln.so.1"
LIBLN_PULL = REPO / "build" / "release" / "libln_pull" / "libln_pull.so.1"


def header_version() -> str:
    text = (REPO / "libln" / "include" / "ln" / "ln.h").read_text()
    found = dict(re.findall(r"^#define LN_VERSION_(MAJOR|MINOR|PATCH) (\d+)$", text, re.M))
    return f"{found['MAJOR']}.{found['MINOR']}.{found['PATCH']}"


def test_versions_agree() -> None:
    changelog = (REPO / "debian" / "changelog").read_text().splitlines()[0]
    match = re.match(r"links-and-nodes \(([^)]+)\) ", changelog)
    assert match, changelog
    assert header_version() == links_and_nodes.__version__ == match.group(1)


def test_pip_installs_every_message_definition_folder() -> None:
    pyproject = tomllib.loads((REPO / "pyproject.toml").read_text())
    data_files = pyproject["tool"]["setuptools"]["data-files"]
    md_root = REPO / "message_definitions"
    prefix = "share/links_and_nodes/message_definitions"
    # Every md file goes to its own folder (nested ones too, e.g. ln/parameters/query), and
    # no pattern matches a folder (setuptools would try to copy it as a file).
    installed: dict[Path, str] = {}
    for dest, patterns in data_files.items():
        for pattern in patterns:
            for path in sorted(REPO.glob(pattern)):
                assert path.is_file(), f"{pattern} matches the folder {path}"
                installed[path] = dest
    wanted = {p: f"{prefix}/{p.parent.relative_to(md_root)}" for p in md_root.rglob("*")
              if p.is_file() and p.name != "SConscript"
              and not any(part.startswith(".") for part in p.relative_to(md_root).parts)}
    assert installed == wanted


def debian_lines(name: str) -> list[str]:
    text = (REPO / "debian" / name).read_text()
    return [line for line in text.splitlines() if line and not line.startswith("#")]


def test_console_scripts_are_packaged_alike() -> None:
    scripts = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]["scripts"]
    # SCons launchers run MODULE.main(): python/SConscript's LAUNCHERS list of
    # ('name', 'module') and literal install_launcher(env, 'name', 'module') calls.
    launchers: dict[str, str] = {}
    for sconscript in ("python/SConscript", "ln_generate/SConscript"):
        text = (REPO / sconscript).read_text()
        launchers.update(re.findall(r"\('(\w+)', '([\w.]+)'\)", text))
        launchers.update(re.findall(r"install_launcher\(env, '(\w+)', '([\w.]+)'\)", text))
    assert {name: f"{module}:main" for name, module in launchers.items()} == scripts
    installed = {line.removeprefix("usr/bin/")
                 for line in debian_lines("python3-links-and-nodes.install")
                 if line.startswith("usr/bin/")}
    assert installed == set(scripts)
    manpages = {Path(line).name for line in debian_lines("python3-links-and-nodes.manpages")}
    assert manpages == {f"{name}.1" for name in scripts}
    assert all((REPO / "debian" / "man" / page).exists() for page in manpages)
    smoke = (REPO / "tests" / "installed" / "run").read_text()
    commands = re.search(r"^for cmd in ([\w ]+); do$", smoke, re.M)
    assert commands, "tests/installed/run no longer checks the commands on PATH"
    assert set(scripts) <= set(commands.group(1).split())
    leftovers = (REPO / "scripts" / "test-packages").read_text()
    assert all(f"-name '{name}*'" in leftovers for name in scripts)


def symbols_sections() -> dict[str, list[str]]:
    """The symbols debian/libln1.symbols lists, by the soname of the section they are in."""
    sections: dict[str, list[str]] = {}
    current: list[str] = []
    for line in (REPO / "debian" / "libln1.symbols").read_text().splitlines():
        if line.startswith(" "):
            current.append(line.split()[0].split("@")[0])
        elif line.strip() and not line.startswith(("#", "|", "*")):
            current = sections.setdefault(line.split()[0], [])
    return sections


@pytest.mark.parametrize("soname, path", [("libln.so.1", LIBLN), ("libln_pull.so.1", LIBLN_PULL)])
def test_symbols_file_lists_exactly_the_exports(soname: str, path: Path) -> None:
    if not path.exists():
        if os.environ.get("CI"):
            pytest.fail(f"{path} is not built")
        pytest.skip(f"{path} is not built")
    out = subprocess.run(["nm", "-D", "--defined-only", str(path)], capture_output=True,
                         text=True, check=True).stdout
    exported = sorted(line.split()[-1] for line in out.splitlines() if line.strip())
    listed = sorted(symbols_sections().get(soname, []))
    assert listed == exported, f"debian/libln1.symbols ({soname}) is out of date: add new " \
                               "symbols with the version that introduces them"
