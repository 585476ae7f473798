"""The native parts a wheel (or an sdist built by pip) carries inside this package: lib/
(libln.so.1, libln_pull.so.1, links_and_nodes/libln_admin.so), bin/ln_daemon and include/ln/
(docs/install.md).  A checkout or the Debian package has none of them: every lookup answers
None there and the callers go on to the build tree and the system.
`python -m links_and_nodes.bundled --cflags --libs` prints the compiler flags for C programs
that use the bundled libln, the way `pkg-config --cflags --libs ln` does for an installed one.
Imports nothing of ours."""

from __future__ import annotations

import argparse
import shlex
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent
LIB = ROOT / "lib"
BIN = ROOT / "bin"
INCLUDE = ROOT / "include"


def shared_object(soname: str) -> Path | None:
    """lib/`soname` of the package, if it carries one."""
    path = LIB / soname
    return path if path.is_file() else None


def program(name: str) -> Path | None:
    """bin/`name` of the package, if it carries it (executable)."""
    path = BIN / name
    return path if path.is_file() else None


def cflags() -> list[str]:
    return [f"-I{INCLUDE}"]


def libs(library_name: str = "ln") -> list[str]:
    """Link `library_name` (ln or ln_pull) by its soname file (a wheel holds no symlinks) and
    find it at run time through an rpath."""
    return [f"-L{LIB}", f"-l:lib{library_name}.so.1", f"-Wl,-rpath,{LIB}"]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m links_and_nodes.bundled",
        description="Compiler flags and paths of the native parts bundled in this package "
                    "(a wheel or an sdist installed by pip).")
    parser.add_argument("--cflags", action="store_true", help="the -I flag of the headers")
    parser.add_argument("--libs", action="store_true", help="the flags that link libln")
    parser.add_argument("--pull", action="store_true", help="--libs links libln_pull instead")
    parser.add_argument("--daemon", action="store_true", help="the path of ln_daemon")
    args = parser.parse_args(argv)
    if shared_object("libln.so.1") is None or not (INCLUDE / "ln" / "ln.h").is_file():
        print(f"links_and_nodes at {ROOT} carries no native parts (a checkout or the Debian "
              "package: use `pkg-config --cflags --libs ln`)", file=sys.stderr)
        return 1
    words: list[str] = []
    if args.cflags:
        words += cflags()
    if args.libs:
        words += libs("ln_pull" if args.pull else "ln")
    if args.daemon:
        words.append(str(BIN / "ln_daemon"))
    if not words:
        parser.error("give at least one of --cflags, --libs, --daemon")
    print(shlex.join(words))
    return 0


if __name__ == "__main__":
    sys.exit(main())
