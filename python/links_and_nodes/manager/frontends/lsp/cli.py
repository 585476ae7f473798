"""`ln_lsp`: reads the command line (without loading pygls, so `--help` and `--version`
answer anywhere), then runs the language server of server.py on stdin/stdout."""

from __future__ import annotations

import argparse
import sys

from .... import __version__


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="ln_lsp",
        description="The language server of links_and_nodes for .lnc configurations and "
                    "message definitions (docs/editors.md); an editor starts it and talks "
                    "to it over stdin and stdout.  Its settings (defines, md directories, "
                    "strict, shell timeout) come from the editor.")
    parser.add_argument("--stdio", action="store_true",
                        help="talk over stdin/stdout (the default and only transport)")
    parser.add_argument("--version", action="version", version=f"ln_lsp {__version__}")
    parser.parse_args(argv)
    try:
        from .server import main as serve
    except ImportError as exc:
        print(f"ln_lsp: {exc}: the language server needs pygls 2 "
              "(pip install 'links_and_nodes[lsp]')", file=sys.stderr)
        return 2
    serve()
    return 0


if __name__ == "__main__":
    sys.exit(main())
