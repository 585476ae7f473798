"""Commands named by a phrase of several words (`logger NAME add TOPIC`, spec.Command.phrase):
which command of a family a console line or `ln_manager` argv names, and the family's usage.
The values standing inside the phrase become the command's first positional words, so the
rest is parsed by check.parse_words like any command's words."""

from __future__ import annotations

from .spec import ArgError, Command
from .table import commands


def family(word: str, where: str = "console") -> list[Command]:
    """The commands whose phrase starts with `word` in front end `where`."""
    return [c for c in commands() if c.family == word
            and (c.console_word if where == "console" else c.cli_word)]


def families(where: str = "console") -> list[str]:
    return list(dict.fromkeys(c.family for c in commands() if c.family
                              and (c.console_word if where == "console" else c.cli_word)))


def said(cmd: Command) -> list[str]:
    """The literal words of its phrase: ["logger", "add"] of `logger NAME add`."""
    words = cmd.phrase.split()
    return words[:1] + [w for w in words[1:] if not w.isupper()]


def usage(word: str, where: str = "console") -> str:
    """`usage: logger ...`: every command of the family, one a line."""
    lines = [c.usage(where) for c in family(word, where)]
    return "usage: " + "\n       ".join(lines)


def _fits(cmd: Command, words: list[str], where: str) -> list[str] | None:
    """The words of the line for parse_words when `words` (the family's word first) say
    this command's phrase, else None.  Its options may come anywhere, also inside the
    phrase (`logger --on-manager NAME save FILE`)."""
    from .check import is_number

    tokens = cmd.phrase.split()[1:]
    options = {a.option: a for a in cmd.args if not a.positional and a.where in ("", where)}
    placed: list[str] = []
    moved: list[str] = []
    it = iter(words[1:])
    for token in tokens:
        word = next(it, None)
        while word is not None and word.startswith("-") and not is_number(word):
            moved.append(word)
            arg = options.get(word)
            if arg is not None and arg.type != "bool":
                moved.append(next(it, ""))
            word = next(it, None)
        if word is None or (token.isupper() and word.startswith("-")):
            return None
        if token.isupper():
            placed.append(word)
        elif token != word:
            return None
    return placed + list(it) + moved


def match(words: list[str], where: str = "console") -> tuple[Command, list[str]]:
    """The command a line of a family says (words: the family's word first) and its words
    for check.parse_words; ArgError with the family's usage when it says none."""
    best: tuple[Command, list[str]] | None = None
    for cmd in family(words[0], where):
        rest = _fits(cmd, words, where)
        if rest is not None and (best is None or len(cmd.phrase.split())
                                 > len(best[0].phrase.split())):
            best = (cmd, rest)
    if best is None or (best[1] and not any(a.positional for a in best[0].args)):
        code = best[0].code if best else ""
        raise ArgError(usage(words[0], where), code)
    return best
