"""The page's files: static/ of this package, and uPlot and dagre (the graph's layout; both
fetched by the build with npm, never checked in) from static/vendor/ of an installed
package or, in a checkout, from the build tree's build/webui/uplot/ and build/webui/dagre/.
Only plain names under those directories are served."""

from __future__ import annotations

import re
from pathlib import Path

STATIC = Path(__file__).resolve().parent / "static"
VENDOR_FILES = ("uPlot.iife.min.js", "uPlot.min.css")
# every vendored file, with the build tree's directory of a checkout that has it
VENDOR = {"uPlot.iife.min.js": "uplot", "uPlot.min.css": "uplot", "dagre.min.js": "dagre"}
_BUILD = Path(__file__).resolve().parents[5] / "build" / "webui"
_NAME = re.compile(r"[A-Za-z0-9_-][A-Za-z0-9_.-]{0,99}")
TYPES = {".html": "text/html; charset=utf-8", ".js": "text/javascript; charset=utf-8",
         ".css": "text/css; charset=utf-8", ".png": "image/png", ".svg": "image/svg+xml",
         ".json": "application/json"}


def vendor_dir() -> Path | None:
    """Where uPlot is: the installed package's static/vendor, else the checkout's build
    tree (python/links_and_nodes/manager/webui -> build/webui/uplot)."""
    candidates = [STATIC / "vendor", _BUILD / "uplot"]
    for d in candidates:
        if all((d / f).is_file() for f in VENDOR_FILES):
            return d
    return None


def find(path: str) -> Path | None:
    """The file for URL path /static/NAME or /static/vendor/NAME; None if there is none
    (or the name is not a plain one: no traversal, no hidden files)."""
    parts = path.split("/")
    if len(parts) == 3 and parts[:2] == ["", "static"]:
        root, name = STATIC, parts[2]
    elif len(parts) == 4 and parts[:3] == ["", "static", "vendor"]:
        name = parts[3]
        if name not in VENDOR:
            return None
        root = next((d for d in (STATIC / "vendor", _BUILD / VENDOR[name])
                     if (d / name).is_file()), None)
    else:
        return None
    if root is None or not _NAME.fullmatch(name) or ".." in name:
        return None
    file = (root / name).resolve()
    if file.parent != root.resolve() or not file.is_file():
        return None
    return file


def content_type(file: Path) -> str:
    return TYPES.get(file.suffix, "application/octet-stream")
