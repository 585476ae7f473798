"""Makes docs/images/editors_highlight.png: examples/robot/robot.lnc with one typo, highlighted
by the Tree-sitter grammar (`tree-sitter highlight --html`), with the diagnostic ln_lsp
publishes for it drawn as an editor would, captured by headless Chromium.
Run from the checkout: python editors/make_screenshot.py [--out PNG]"""

from __future__ import annotations

import argparse
import html
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]
SAMPLE = REPO / "examples" / "robot" / "robot.lnc"
TYPO = ("    depends_on: sensor  ", "    depends_on: sensr   ")
LINES = (7, 45)  # the part of the file shown
# VS Code's dark colours for the captures of the grammars' queries/highlights.scm.
THEME = {
    "comment": {"color": "#6a9955", "italic": True}, "keyword": {"color": "#c586c0", "bold": True},
    "keyword.type": "#569cd6", "type": "#4ec9b0", "type.builtin": "#569cd6",
    "property": "#9cdcfe", "label": "#dcdcaa", "variable": "#9cdcfe", "string": "#ce9178",
    "string.special": "#d7ba7d", "string.escape": "#d7ba7d", "number": "#b5cea8",
    "boolean": "#569cd6", "constant": "#4fc1ff", "constant.builtin": "#569cd6",
    "function.builtin": "#dcdcaa", "function.macro": "#dcdcaa", "operator": "#d4d4d4",
    "punctuation.bracket": "#ffd700", "punctuation.special": "#569cd6",
    "punctuation.delimiter": "#808080",
}
PAGE_STYLE = """
body { margin:0; background:#1e1e1e; color:#d4d4d4; font:14px 'DejaVu Sans Mono',monospace; }
.ui { font-family:'DejaVu Sans',sans-serif; font-size:13px; }
.tabs { background:#252526; height:34px; }
.tab { display:inline-block; background:#1e1e1e; color:#fff; padding:8px 16px;
       border-top:1px solid #0078d4; }
.row { white-space:pre; line-height:19px; }
.ln { display:inline-block; width:4ch; text-align:right; color:#858585; margin-right:2ch; }
.squiggle { text-decoration:underline wavy #f14c4c; text-underline-offset:3px; }
.hover { display:inline-block; background:#252526; border:1px solid #454545; color:#ccc;
         padding:4px 8px; margin:2px 0 4px; }
.dim { color:#858585; }
.panel { border-top:1px solid #414141; padding:6px 16px 14px; }
.title { color:#e7e7e7; font-size:11px; letter-spacing:1px; border-bottom:1px solid #e7e7e7;
         display:inline-block; padding-bottom:3px; margin-bottom:8px; }
.err { color:#f14c4c; }
"""


def highlight(tree_sitter: str, source: Path, work: Path) -> list[str]:
    """The lines of `source` as HTML, highlighted by editors/tree-sitter-lnc; and its CSS."""
    config = work / "config.json"
    config.write_text(json.dumps({"parser-directories": [str(REPO / "editors")],
                                  "theme": THEME}))
    env = {**os.environ, "TREE_SITTER_LIBDIR": str(work / "lib")}
    page = subprocess.run([tree_sitter, "highlight", "--config-path", str(config), "--html",
                           "--scope", "source.lnc", str(source)], env=env, check=True,
                          capture_output=True, text=True, timeout=600).stdout
    style = re.search(r"<style>(.*?)</style>", page, re.S)
    code = re.search(r"<pre><code>(.*?)</code></pre>", page, re.S)
    if not style or not code:
        raise SystemExit("tree-sitter highlight --html gave no <style> or <pre><code>")
    return [style.group(1).replace("font-family: monospace", ""),
            *code.group(1).rstrip("\n").split("\n")]


def _message(stream: Any) -> dict[str, Any]:
    length = 0
    while line := stream.readline().strip():
        name, _, value = line.decode().partition(":")
        if name.lower() == "content-length":
            length = int(value)
    return json.loads(stream.read(length))


def diagnostics(source: Path) -> list[dict[str, Any]]:
    """What ln_lsp publishes for `source` once it is opened (JSON-RPC over its stdio)."""
    server = subprocess.Popen([sys.executable, "-m", "links_and_nodes.manager.frontends.lsp"],
                              stdin=subprocess.PIPE, stdout=subprocess.PIPE)
    assert server.stdin is not None and server.stdout is not None

    def send(message: dict[str, Any]) -> None:
        body = json.dumps({"jsonrpc": "2.0", **message}).encode()
        server.stdin.write(b"Content-Length: %d\r\n\r\n%s" % (len(body), body))
        server.stdin.flush()

    try:
        send({"id": 1, "method": "initialize", "params": {
            "processId": None, "rootUri": source.parent.as_uri(), "capabilities": {}}})
        while _message(server.stdout).get("id") != 1:
            pass
        send({"method": "initialized", "params": {}})
        send({"method": "textDocument/didOpen", "params": {"textDocument": {
            "uri": source.as_uri(), "languageId": "lnc", "version": 1,
            "text": source.read_text()}}})
        while (message := _message(server.stdout)).get("method") != \
                "textDocument/publishDiagnostics":
            pass
        return message["params"]["diagnostics"]
    finally:
        server.kill()
        server.wait()


def page(lines: list[str], source: Path, diagnostic: dict[str, Any]) -> str:
    style, code = lines[0], lines[1:]
    start, end = diagnostic["range"]["start"], diagnostic["range"]["end"]
    line, col = start["line"] + 1, start["character"] + 1
    word = source.read_text().splitlines()[line - 1][start["character"]:end["character"]]
    code[line - 1] = code[line - 1].replace(word, f"<span class='squiggle'>{word}</span>", 1)
    message = html.escape(diagnostic["message"])
    where = html.escape(diagnostic.get("source", "ln_lsp"))
    rows = []
    for number in range(LINES[0], LINES[1] + 1):
        rows.append(f"<div class='row'><span class='ln'>{number}</span>{code[number - 1]}</div>")
        if number == line:
            indent = " " * (col + 5)  # past the line numbers (6 columns), under the word
            rows.append(f"<div class='row'>{indent}<span class='hover ui'>{message} "
                        f"<span class='dim'>{where}</span></span></div>")
    return (f"<!doctype html><html><head><meta charset='utf-8'><style>{PAGE_STYLE}{style}"
            f"</style></head><body><div class='tabs ui'><div class='tab'>{source.name}</div>"
            f"</div><div style='padding:6px 0'>{''.join(rows)}</div><div class='panel ui'>"
            f"<div class='title'>PROBLEMS</div><div><span class='err'>&#x2297;</span> "
            f"{message} <span class='dim'>{where} [Ln {line}, Col {col}]</span></div></div>"
            f"</body></html>")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=REPO / "docs/images/editors_highlight.png")
    parser.add_argument("--tree-sitter", default=shutil.which("tree-sitter")
                        or str(Path.home() / ".cargo/bin/tree-sitter"))
    parser.add_argument("--chromium", default="chromium")
    parser.add_argument("--size", default="1000,895", help="window WIDTH,HEIGHT in pixels")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        source = work / "robot" / SAMPLE.name
        source.parent.mkdir()
        text = SAMPLE.read_text()
        if text.count(TYPO[0]) != 1:
            raise SystemExit(f"{SAMPLE}: the line to misspell ({TYPO[0].strip()!r}) is gone")
        source.write_text(text.replace(*TYPO))
        found = diagnostics(source)
        if len(found) != 1:
            raise SystemExit(f"ln_lsp published {len(found)} diagnostics, not 1: {found}")
        (work / "page.html").write_text(page(highlight(args.tree_sitter, source, work), source,
                                             found[0]))
        subprocess.run([args.chromium, "--headless", "--no-sandbox", "--disable-gpu",
                        "--hide-scrollbars", f"--screenshot={args.out.resolve()}",
                        f"--window-size={args.size}", (work / "page.html").as_uri()],
                       check=True, capture_output=True, timeout=120)
    print(f"{args.out}: {found[0]['message']}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
