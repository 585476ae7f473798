"""Writes the TextMate grammars of the VS Code extension (syntaxes/lnc.tmLanguage.json and
syntaxes/lnmd.tmLanguage.json) from the word tables of the `.lnc` reader and of ln_generate,
so that the editor colours exactly the keys, flags and types the readers know.
Run from the checkout: `python editors/vscode/tools/make_grammars.py` (`--check`: exit 1 if
the files differ from what would be written; tests/python/editors/test_vsix.py runs it)."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[2]
SYNTAXES = HERE.parent / "syntaxes"
for _p in (REPO / "python", REPO):
    if str(_p) not in sys.path:
        sys.path.insert(0, str(_p))

from links_and_nodes.manager.config import expand, keywords, lexer, process_keys  # noqa: E402
from links_and_nodes.manager.config import sections as lnc_sections  # noqa: E402
from ln_generate import model as md_model  # noqa: E402

Rule = dict[str, Any]
SCHEMA = "https://raw.githubusercontent.com/martinring/tmlanguage/master/tmlanguage.json"
LINE = r"(?:^|\G)\s*"  # a line's start, or where `ifdef NAME:` hands the rest of the line on
COLON = r"\s*(:)"
SIMPLE_SECTIONS = ("instance", "defines", "hosts", "node_map", "topics",
                   "access")  # no name after them
INCLUDES = ("include", "optional_include", "include_glob", "optional_include_glob",
            "pipe_include")
CONSTANTS = ("true", "false", "on", "off", "never", "on-failure", "always", "udp", "tcp",
             "ndn-udp", "unlimited", "infinity", "localhost", "SCHED_OTHER", "SCHED_FIFO",
             "SCHED_RR")


def alternation(words: set[str] | tuple[str, ...] | frozenset[str]) -> str:
    """`(?:a|b)` of `words`, longest first, so that no word stops at a shorter one's end."""
    return "(?:" + "|".join(sorted(set(words), key=lambda w: (-len(w), w))) + ")"


def key_line(words: str, key_scope: str, value: str = "#value") -> Rule:
    return {"begin": LINE + r"(?:(add)\s+)?(" + words + r")(?=\s*:)" + COLON,
            "beginCaptures": {"1": {"name": "storage.modifier.add.lnc"},
                              "2": {"name": key_scope},
                              "3": {"name": "punctuation.separator.key-value.lnc"}},
            "end": "$", "patterns": [{"include": value}]}


def lnc_keys() -> list[Rule]:
    """Key lines: known keys, keys the reader ignores, keys it refuses, and any other
    `NAME:` (defines, hosts, node_map, topic and logger patterns)."""
    known = (set(process_keys.SCALARS) | set(process_keys.LISTS) | keywords.OTHER_KEYS
             | lnc_sections.StateSection.KEYS | lnc_sections.GroupSection.KEYS
             | {"use_template", "autostart"}) - {"flags", "undef"}
    ignored = set(process_keys.IGNORED) | set(lnc_sections.InstanceSection.IGNORED)
    refused = (set(process_keys.UNSUPPORTED) | set(keywords.REFUSED_ELSEWHERE)) - {"undef"}
    other = r'"(?:[^"\\]|\\.)*"|(?:[^\s:#"%]|%\((?:[^()]|\([^()]*\))*\))+'
    return [
        key_line("flags", "support.type.property-name.lnc", "#flags-value"),
        key_line(alternation(known), "support.type.property-name.lnc"),
        key_line(alternation(ignored - known), "support.type.property-name.ignored.lnc"),
        key_line(alternation(refused), "invalid.deprecated.unsupported.lnc"),
        key_line(other, "variable.other.key.lnc"),
    ]


def lnc_headers() -> list[Rule]:
    named = set(lexer.SECTION_WORDS) - set(SIMPLE_SECTIONS) - {"template", "process_template"}
    return [
        {"match": LINE + "(" + alternation(SIMPLE_SECTIONS) + r")(?=\s*(?:#|$))",
         "captures": {"1": {"name": "storage.type.section.lnc"}}},
        {"begin": LINE + r"(template|process_template)\s+([^\s(#]+)",
         "beginCaptures": {"1": {"name": "storage.type.section.lnc"},
                           "2": {"name": "entity.name.function.template.lnc"}},
         "end": r"(?=#)|$", "patterns": [{"include": "#parameters"}]},
        {"begin": LINE + "(" + alternation(named) + r")(?=\s|$)(?!\s*:)",
         "beginCaptures": {"1": {"name": "storage.type.section.lnc"}},
         "end": r"(?=#)|$", "contentName": "entity.name.function.lnc",
         "patterns": [{"include": "#string"}, {"include": "#call"}]},
    ]


def lnc_directives() -> list[Rule]:
    others = (keywords.DIRECTIVES - set(INCLUDES) - {"use_template"}) | {"undef"}
    rules = []
    for words, scope in ((INCLUDES, "keyword.control.import.lnc"),
                         (others, "keyword.control.directive.lnc")):
        rules.append({"begin": LINE + "(" + alternation(words) + r")(?=[\s:]|$)\s*(:)?",
                      "beginCaptures": {"1": {"name": scope},
                                        "2": {"name": "punctuation.separator.key-value.lnc"}},
                      "end": r"(?=#)|$", "patterns": [
                          {"match": r"(?:(?<=\s)|\G)(!)", "name": "keyword.operator.negation.lnc"},
                          {"include": "#string"}, {"include": "#call"}]})
    rules.append({"begin": LINE + r"(ifdef|ifndef)\s+((?:[^\s:%#]|%\([^()]*\))+)" + COLON + r"\s*",
                  "beginCaptures": {"1": {"name": "keyword.control.conditional.lnc"},
                                    "2": {"name": "variable.other.define.lnc"},
                                    "3": {"name": "punctuation.separator.key-value.lnc"}},
                  "end": "$", "patterns": [{"include": "#line"}]})
    rules.append({"begin": LINE + r"(append)\s+(environment)\b\s*([^\s:#]*)" + COLON,
                  "beginCaptures": {"1": {"name": "storage.modifier.append.lnc"},
                                    "2": {"name": "support.type.property-name.lnc"},
                                    "3": {"name": "variable.other.environment.lnc"},
                                    "4": {"name": "punctuation.separator.key-value.lnc"}},
                  "end": "$", "patterns": [{"include": "#value"}]})
    return rules


def lnc_values() -> dict[str, Rule]:
    atoms = [{"include": "#string"}, {"include": "#call"},
             {"match": r"\b" + alternation(CONSTANTS) + r"(?![\w-])",
              "name": "constant.language.lnc"},
             {"match": r"\bSIG[A-Z0-9]+\b", "name": "constant.language.signal.lnc"},
             {"match": r"(?<![\w./:-])-?\d+(?:\.\d+)?(?:ms|s|min|h|[KMGTkmgt](?:i?[Bb])?)?"
                       r"(?![\w./:-])", "name": "constant.numeric.lnc"},
             {"match": ",", "name": "punctuation.separator.comma.lnc"}]
    flags = set(process_keys.FLAGS) | set(lnc_sections.GROUP_FLAGS)
    block = {"begin": r"\G\s*(\[)\s*(?=#|$)",
             "beginCaptures": {"1": {"name": "punctuation.section.block.begin.lnc"}},
             "end": r"^\s*(\])",
             "endCaptures": {"1": {"name": "punctuation.section.block.end.lnc"}},
             "name": "meta.block.lnc",
             "patterns": [{"match": r"(?:\G|^)\s*(#.*)$",
                           "captures": {"1": {"name": "comment.line.number-sign.lnc"}}},
                          {"include": "#flag"}, *atoms]}
    return {
        "value": {"patterns": [
            block, {"include": "#comment"},
            {"match": r"(?:\G|(?<=,))\s*(!)?([A-Za-z_][\w.-]*)(:)(?![/\\])",
             "captures": {"1": {"name": "keyword.operator.negation.lnc"},
                          "2": {"name": "entity.other.attribute-name.lnc"},
                          "3": {"name": "punctuation.separator.setting.lnc"}}},
            {"match": r"(?:\G|(?<=,))\s*(!)", "name": "keyword.operator.negation.lnc"},
            *atoms]},
        "flag": {"match": r"\b" + alternation(flags) + r"\b", "name": "constant.language.flag.lnc"},
        "flags-value": {"patterns": [{"include": "#flag"}, {"include": "#value"}]},
        "comment": {"match": r"(#).*$", "name": "comment.line.number-sign.lnc",
                    "captures": {"1": {"name": "punctuation.definition.comment.lnc"}}},
        "string": {"begin": '"', "end": '"', "name": "string.quoted.double.lnc",
                   "beginCaptures": {"0": {"name": "punctuation.definition.string.begin.lnc"}},
                   "endCaptures": {"0": {"name": "punctuation.definition.string.end.lnc"}},
                   "patterns": [{"match": r'\\["\\]', "name": "constant.character.escape.lnc"},
                                {"include": "#call"}]},
        "call": {"begin": r"%\(", "end": r"\)", "name": "meta.interpolation.lnc",
                 "beginCaptures": {"0": {"name": "punctuation.section.embedded.begin.lnc"}},
                 "endCaptures": {"0": {"name": "punctuation.section.embedded.end.lnc"}},
                 "patterns": [
                     {"include": "#call"},
                     {"match": r"\G\s*" + alternation(expand.FUNCTIONS) + r"(?=\s|$)",
                      "name": "support.function.builtin.lnc"},
                     {"match": r"\G\s*" + alternation(expand.CONTEXT_BUILTINS
                                                      + expand.GLOBAL_BUILTINS) + r"(?=\s*\))",
                      "name": "variable.language.lnc"},
                     {"match": r"\G\s*[^\s()\"%,]+", "name": "variable.other.define.lnc"},
                     {"include": "#string"},
                     {"match": ",", "name": "punctuation.separator.arguments.lnc"},
                     {"begin": r"\(", "end": r"\)", "patterns": [{"include": "#call"}]}]},
        "parameters": {"begin": r"\(", "end": r"\)",
                       "beginCaptures": {
                           "0": {"name": "punctuation.definition.parameters.begin.lnc"}},
                       "endCaptures": {
                           "0": {"name": "punctuation.definition.parameters.end.lnc"}},
                       "patterns": [
                           {"match": r"(?:\G|(?<=,))\s*([A-Za-z_][\w.-]*)\s*(=)?",
                            "captures": {"1": {"name": "variable.parameter.lnc"},
                                         "2": {"name": "keyword.operator.assignment.lnc"}}},
                           {"include": "#string"}, {"include": "#call"},
                           {"match": ",", "name": "punctuation.separator.parameters.lnc"}]},
    }


def lnc_grammar() -> Rule:
    line = [{"include": "#comment"}, *lnc_headers(), *lnc_directives(), *lnc_keys()]
    return {"$schema": SCHEMA,
            "name": "Links and Nodes configuration", "scopeName": "source.lnc",
            "fileTypes": ["lnc"],
            "comment": "Generated by editors/vscode/tools/make_grammars.py from the .lnc reader's "
                       "tables (docs/configuration.md); do not edit.",
            "patterns": [{"include": "#line"}],
            "repository": {"line": {"patterns": line}, **lnc_values()}}


def lnmd_grammar() -> Rule:
    sections = {name for names in md_model.SECTIONS.values() for name in names if name}
    kinds = {kind for kind in md_model.SECTIONS if kind in ("service", "event")}
    number = {"patterns": [{"match": r"\b(?:0[xX][0-9A-Fa-f]+|\d+)\b",
                            "name": "constant.numeric.lnmd"},
                           {"match": r"[-+*/]", "name": "keyword.operator.arithmetic.lnmd"}]}
    return {"$schema": SCHEMA,
            "name": "Links and Nodes message definition", "scopeName": "source.lnmd",
            "comment": "Generated by editors/vscode/tools/make_grammars.py from ln_generate's "
                       "tables (docs/message_definitions.md); do not edit.",
            "patterns": [
                {"match": r"(#).*$", "name": "comment.line.number-sign.lnmd",
                 "captures": {"1": {"name": "punctuation.definition.comment.lnmd"}}},
                {"match": r"^\s*" + alternation(kinds) + r"(?=\s*(?:#|$))",
                 "name": "keyword.control.kind.lnmd"},
                {"match": r"^\s*" + alternation(sections - kinds) + r"(?=\s*(?:#|$))",
                 "name": "storage.type.section.lnmd"},
                {"match": r'^\s*(define)\s+([A-Za-z_]\w*)\s+(as)\s+("[^"]*")',
                 "captures": {"1": {"name": "keyword.other.define.lnmd"},
                              "2": {"name": "entity.name.type.alias.lnmd"},
                              "3": {"name": "keyword.other.as.lnmd"},
                              "4": {"name": "string.quoted.double.lnmd"}}},
                {"match": r"^\s*(?:(" + alternation(md_model.TYPE_NAMES)
                          + r")(?!\w)|([A-Za-z_]\w*))"
                          r"\s*(\*)?\s*([A-Za-z_]\w*)\s*(?:(\[)([^\]#]*)(\]))?",
                 "captures": {"1": {"name": "storage.type.builtin.lnmd"},
                              "2": {"name": "entity.name.type.lnmd"},
                              "3": {"name": "storage.modifier.pointer.lnmd"},
                              "4": {"name": "variable.other.field.lnmd"},
                              "5": {"name": "punctuation.definition.array.begin.lnmd"},
                              "6": number,
                              "7": {"name": "punctuation.definition.array.end.lnmd"}}}]}


def rendered() -> dict[Path, str]:
    """The text of each grammar file, as this script writes it."""
    return {SYNTAXES / "lnc.tmLanguage.json": json.dumps(lnc_grammar(), indent=2) + "\n",
            SYNTAXES / "lnmd.tmLanguage.json": json.dumps(lnmd_grammar(), indent=2) + "\n"}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true",
                        help="write nothing; exit 1 if a grammar file is not up to date")
    args = parser.parse_args()
    stale = [path for path, text in rendered().items()
             if not path.exists() or path.read_text(encoding="utf-8") != text]
    if args.check:
        for path in stale:
            print(f"{path.relative_to(REPO)}: not up to date (run {Path(__file__).name})",
                  file=sys.stderr)
        return 1 if stale else 0
    for path in stale:
        path.write_text(rendered()[path], encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
