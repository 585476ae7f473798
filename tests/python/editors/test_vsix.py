"""The VS Code extension (editors/vscode): scripts/build-vsix packs it, with npm's packages
fetched by `npm ci`, into a .vsix holding the manifest with the project's version, both
TextMate grammars and the language client; the grammars are what tools/make_grammars.py makes
from the readers' tables, and vscode-textmate (VS Code's tokenizer, fetched by the same
`npm ci`) gives the expected scopes on hand-written samples and reads the project's files."""

from __future__ import annotations

import importlib.util
import json
import re
import shutil
import subprocess
import zipfile
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import Any

import pytest
from buildtree import REPO, missing_test_tool

VSCODE = REPO / "editors" / "vscode"
REAL = REPO.parent / "shared" / "real_ln"


def load_module(name: str, path: Path) -> ModuleType:
    spec = importlib.util.spec_from_file_location(name, path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


LN_VERSION = load_module("ln_version", REPO / "site_scons" / "ln_version.py")
VERSION = LN_VERSION.version_string(
    LN_VERSION.version_macros((REPO / "libln" / "include" / "ln" / "ln.h").read_text()))


@dataclass(frozen=True)
class Build:
    vsix: Path
    stage: Path  # the copy build-vsix packed, with its node_modules


@pytest.fixture(scope="module")
def build(tmp_path_factory: pytest.TempPathFactory) -> Build:
    for tool in ("node", "npm"):
        if shutil.which(tool) is None:
            missing_test_tool(f"{tool} (scripts/setup installs npm)")
    tmp = tmp_path_factory.mktemp("vsix")
    result = subprocess.run([str(REPO / "scripts" / "build-vsix"), "--out", str(tmp / "out"),
                             "--stage", str(tmp / "stage")],
                            capture_output=True, text=True, timeout=900)
    if result.returncode == 3:
        ping = subprocess.run(["npm", "ping"], capture_output=True, text=True, timeout=120)
        if ping.returncode != 0:
            missing_test_tool(f"the npm registry (npm ping: {ping.stderr.strip()[-200:]})")
    assert result.returncode == 0, result.stdout + result.stderr
    return Build(tmp / "out" / f"links-and-nodes-{VERSION}.vsix", tmp / "stage")


def tokenize(build: Build, scope: str, files: list[Path]) -> dict[str, Any]:
    result = subprocess.run(["node", str(build.stage / "tools" / "tokenize.js"), scope,
                             *map(str, files)],
                            capture_output=True, text=True, timeout=300, check=True)
    out = json.loads(result.stdout)
    assert out["regexErrors"] == []
    return out["files"]


def scopes_of(lines: list[list[dict[str, Any]]], line: int, text: str) -> list[str]:
    """The scopes of the first token on `line` (0-based) whose text, stripped, is `text`;
    none if there is no such token."""
    for token in lines[line]:
        if token["text"].strip() == text:
            return token["scopes"]
    return []


def test_vsix_holds_manifest_grammars_and_client(build: Build) -> None:
    assert build.vsix.is_file(), f"{build.vsix} not made"
    with zipfile.ZipFile(build.vsix) as vsix:
        names = set(vsix.namelist())
        manifest = json.loads(vsix.read("extension/package.json"))
        vsixmanifest = vsix.read("extension.vsixmanifest").decode()
    assert manifest["version"] == VERSION
    assert re.search(rf'<Identity [^>]*Version="{re.escape(VERSION)}"', vsixmanifest)
    assert manifest["main"] == "./extension.js"
    assert {lang["id"] for lang in manifest["contributes"]["languages"]} == {"lnc", "lnmd"}
    grammars = {g["scopeName"]: g["path"] for g in manifest["contributes"]["grammars"]}
    assert grammars == {"source.lnc": "./syntaxes/lnc.tmLanguage.json",
                        "source.lnmd": "./syntaxes/lnmd.tmLanguage.json"}
    for path in [*grammars.values(), "./extension.js", "./language-configuration.json",
                 "./language-configuration-md.json", "./LICENSE.txt"]:
        assert "extension/" + path.removeprefix("./") in names, path
    # The client's runtime dependency is bundled; build-only packages and tools are not.
    assert "extension/node_modules/vscode-languageclient/package.json" in names
    assert not any(n.startswith(("extension/node_modules/@vscode/vsce/", "extension/tools/",
                                 "extension/node_modules/vscode-textmate/")) for n in names)
    settings = manifest["contributes"]["configuration"]["properties"]
    assert {"ln.server.path", "ln.defines", "ln.mdDirs", "ln.strict"} <= set(settings)


def test_grammars_are_made_from_the_readers_tables() -> None:
    make = load_module("make_grammars", VSCODE / "tools" / "make_grammars.py")
    for path, text in make.rendered().items():
        assert path.read_text(encoding="utf-8") == text, f"{path}: run make_grammars.py"
        json.loads(text)


LNC_SAMPLE = """\
# robot.lnc
instance
name: robot
defines
bin: /opt/robot/bin
process arm
    command: %(bin)/arm --rate %(env RATE, 1000)
    flags: no_pty, start_in_shell
    depends_on: "camera"
    map_topic: arm.state
    environment: [
        LANG=C.UTF-8
    ]
include parts/arm.inc.lnc  # more
ifdef sim: add depends_on: simulator
template rt(prio, policy="SCHED_FIFO")
    priority: %(prio)
    term_timeout: 2.5s
"""

LNC_EXPECTED = [  # (line, token, scope the token has)
    (0, "robot.lnc", "comment.line.number-sign.lnc"),
    (1, "instance", "storage.type.section.lnc"),
    (2, "name", "support.type.property-name.lnc"),
    (4, "bin", "variable.other.key.lnc"),
    (5, "process", "storage.type.section.lnc"),
    (5, "arm", "entity.name.function.lnc"),
    (6, "command", "support.type.property-name.lnc"),
    (6, "%(", "punctuation.section.embedded.begin.lnc"),
    (6, "bin", "variable.other.define.lnc"),
    (6, "env", "support.function.builtin.lnc"),
    (7, "no_pty", "constant.language.flag.lnc"),
    (7, "start_in_shell", "constant.language.flag.lnc"),
    (8, "camera", "string.quoted.double.lnc"),
    (9, "map_topic", "invalid.deprecated.unsupported.lnc"),
    (10, "[", "punctuation.section.block.begin.lnc"),
    (11, "LANG=C.UTF-8", "meta.block.lnc"),
    (12, "]", "punctuation.section.block.end.lnc"),
    (13, "include", "keyword.control.import.lnc"),
    (13, "more", "comment.line.number-sign.lnc"),
    (14, "ifdef", "keyword.control.conditional.lnc"),
    (14, "sim", "variable.other.define.lnc"),
    (14, "add", "storage.modifier.add.lnc"),
    (14, "depends_on", "support.type.property-name.lnc"),
    (15, "template", "storage.type.section.lnc"),
    (15, "rt", "entity.name.function.template.lnc"),
    (15, "prio", "variable.parameter.lnc"),
    (15, "SCHED_FIFO", "string.quoted.double.lnc"),
    (16, "prio", "variable.other.define.lnc"),
    (17, "2.5s", "constant.numeric.lnc"),
]

LNMD_SAMPLE = """\
# Plan a path.
define joint_state as "robot/joint_state"
service
request
double goal[6*6]   # rad
joint_state* waypoints
response
int32_t status
"""

LNMD_EXPECTED = [
    (0, "Plan a path.", "comment.line.number-sign.lnmd"),
    (1, "define", "keyword.other.define.lnmd"),
    (1, "joint_state", "entity.name.type.alias.lnmd"),
    (1, '"robot/joint_state"', "string.quoted.double.lnmd"),
    (2, "service", "keyword.control.kind.lnmd"),
    (3, "request", "storage.type.section.lnmd"),
    (4, "double", "storage.type.builtin.lnmd"),
    (4, "goal", "variable.other.field.lnmd"),
    (4, "6", "constant.numeric.lnmd"),
    (4, "*", "keyword.operator.arithmetic.lnmd"),
    (4, "rad", "comment.line.number-sign.lnmd"),
    (5, "joint_state", "entity.name.type.lnmd"),
    (5, "*", "storage.modifier.pointer.lnmd"),
    (7, "int32_t", "storage.type.builtin.lnmd"),
]


@pytest.mark.parametrize(("scope", "sample", "expected"), [
    ("source.lnc", LNC_SAMPLE, LNC_EXPECTED), ("source.lnmd", LNMD_SAMPLE, LNMD_EXPECTED)])
def test_grammar_scopes_on_a_sample(build: Build, tmp_path: Path, scope: str, sample: str,
                                    expected: list[tuple[int, str, str]]) -> None:
    path = tmp_path / "sample"
    path.write_text(sample)
    lines = tokenize(build, scope, [path])[str(path)]
    wrong = [(line, text, want, scopes_of(lines, line, text))
             for line, text, want in expected if want not in scopes_of(lines, line, text)]
    assert wrong == []


SECTION_LINE = re.compile(r"\s*(process|state|group|template|process_template)\s")


def test_lnc_grammar_keeps_in_step_over_whole_files(build: Build) -> None:
    """No rule runs past its line: in every file every section header, wherever it is,
    is read as one, and a top-level comment line is a comment."""
    files = sorted(REPO.glob("examples/**/*.lnc"))
    if REAL.is_dir():
        files += sorted(p for p in (REAL / "lnc").rglob("*.lnc*") if p.is_file())
    assert files
    checked = 0
    for name, lines in tokenize(build, "source.lnc", files).items():
        text = Path(name).read_text().splitlines()
        for number, line in enumerate(text):
            first = lines[number][0]
            if SECTION_LINE.match(line) and ":" not in line.split()[0]:
                assert "storage.type.section.lnc" in scopes_of(lines, number,
                                                               line.split()[0]), (name, line)
                checked += 1
            elif line.startswith("#"):
                assert first["scopes"][-1].startswith("comment.") or \
                    "comment.line.number-sign.lnc" in lines[number][-1]["scopes"], (name, line)
    assert checked > 0


def test_md_grammar_reads_every_builtin_definition(build: Build) -> None:
    files = sorted(p for p in (REPO / "message_definitions").rglob("*")
                   if p.is_file() and "." not in p.name and p.name != "SConscript")
    assert files
    for name, lines in tokenize(build, "source.lnmd", files).items():
        for number, line in enumerate(Path(name).read_text().splitlines()):
            if line.strip() and not line.lstrip().startswith("#"):
                # every construct line starts with a recognised token
                assert len(lines[number][0]["scopes"]) > 1 or \
                    len(lines[number][1]["scopes"]) > 1, (name, line)


# extension.js run by node against a stand-in for VS Code's API and the language client: what
# it starts, with which settings, and which plain-text files it turns into mds.
CLIENT_HARNESS = r"""
const Module = require('module');
const seen = { clients: [], languages: [], errors: [] };
const settings = { 'server.path': '/opt/ln/bin/ln_lsp', defines: ['robot=sim'], strict: true,
                   shellTimeout: 5, mdDirs: ['msgs'] };
const disposable = { dispose() {} };
const doc = (fsPath, languageId) => ({ uri: { scheme: 'file', fsPath }, languageId });
const vscode = {
  workspace: {
    workspaceFolders: [{ uri: { fsPath: '/ws' } }],
    getConfiguration: () => ({ get: (key, dflt) => (key in settings ? settings[key] : dflt) }),
    textDocuments: [doc('/ws/src/message_definitions/robot/pose', 'plaintext'),
                    doc('/ws/message_definitions/SConscript', 'plaintext'),
                    doc('/ws/message_definitions/notes.txt', 'plaintext'),
                    doc('/ws/msgs/arm/state', 'plaintext'),
                    doc('/ws/other/state', 'plaintext'),
                    doc('/ws/robot.lnc', 'lnc'), doc('/ws/parts/arm.inc.lnc', 'lnc')],
    onDidOpenTextDocument: () => disposable,
    onDidChangeConfiguration: () => disposable,
  },
  window: { createOutputChannel: () => disposable,
            showErrorMessage: (text) => seen.errors.push(text) },
  commands: { registerCommand: () => disposable },
  languages: { setTextDocumentLanguage: (d, id) => seen.languages.push([d.uri.fsPath, id]) },
};
class LanguageClient {
  constructor(id, name, server, client) {
    seen.clients.push({ id, command: server.command, args: server.args,
                        init: client.initializationOptions,
                        languages: client.documentSelector.map((s) => s.language) });
  }
  start() { return Promise.resolve(); }
  stop() { return Promise.resolve(); }
}
const load = Module._load;
Module._load = function (request, ...rest) {
  if (request === 'vscode') return vscode;
  if (request === 'vscode-languageclient/node') return { LanguageClient, TransportKind: {} };
  return load.call(this, request, ...rest);
};
require(process.argv[1]).activate({ subscriptions: [] });
setImmediate(() => process.stdout.write(JSON.stringify(seen)));
"""


def test_client_starts_ln_lsp_once_with_the_settings() -> None:
    if shutil.which("node") is None:
        missing_test_tool("node (scripts/setup installs npm)")
    result = subprocess.run(["node", "-e", CLIENT_HARNESS, str(VSCODE / "extension.js")],
                            capture_output=True, text=True, timeout=60, check=True)
    seen = json.loads(result.stdout)
    assert seen["errors"] == []
    assert seen["languages"] == [["/ws/src/message_definitions/robot/pose", "lnmd"],
                                 ["/ws/msgs/arm/state", "lnmd"]]
    assert seen["clients"] == [{
        "id": "ln", "command": "/opt/ln/bin/ln_lsp", "args": [], "languages": [
            "lnc", "lnc", "lnmd", "lnmd"],
        "init": {"defines": ["robot=sim"], "strict": True, "shellTimeout": 5,
                 "mdDirs": ["/ws/msgs"]}}]
