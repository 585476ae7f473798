"""Commands named by a phrase of several words (`logger NAME add TOPIC`, spec.Command.phrase):
which command of a family a console line or `ln_manager` argv names, and the family's usage.
The values standing inside the phrase become the command's first positional words, so the
rest is parsed by check.parse_words like any command's words."""

from __future__ import annotations

from ....tools.commands.spec import ArgError, Command
from ....tools.commands.table import commands, verb


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
    from ....tools.commands.arguments import is_number

    tokens = cmd.phrase.split()[1:]
    options = {spelling: a for a in cmd.args if not a.positional and a.at(where)
               for spelling in (a.option, a.short) if spelling}
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


def _choose(word: str, words: list[str], where: str) -> None:
    """The family's own text for a line that names none of its commands (Verb.choose)."""
    about = verb(word)
    if about is None or not about.choose:
        return
    known = sorted({said(c)[1] for c in family(word, where) if len(said(c)) > 1})
    rest = [w for w in words[1:] if not w.startswith("-")]
    got = f"unknown {word} {about.choose} {rest[0]!r}" if rest else \
        f"{word} needs a {about.choose}"
    raise ArgError(f"{got} (one of: {', '.join(known)})")


def match(words: list[str], where: str = "console") -> tuple[Command, list[str]]:
    """The command a line of a family says (words: the family's word first) and its words
    for check.parse_words; ArgError with the family's usage (or its Verb.choose text) when
    it says none."""
    best: tuple[Command, list[str]] | None = None
    for cmd in family(words[0], where):
        rest = _fits(cmd, words, where)
        if rest is not None and (best is None or len(cmd.phrase.split())
                                 > len(best[0].phrase.split())):
            best = (cmd, rest)
    if best is None:
        _choose(words[0], words, where)
    if best is None or (best[1] and not any(a.positional for a in best[0].args)):
        code = best[0].code if best else ""
        raise ArgError(usage(words[0], where), code)
    return best


def following(before: list[str], where: str = "console") -> list[str]:
    """What may come after the words `before` (the family's word first) of a line being
    typed: the next word of the phrases they begin, or the options of the command they
    say."""
    found: list[str] = []
    for cmd in family(before[0], where):
        tokens = cmd.phrase.split()[1:]
        words = [w for w in before[1:] if not w.startswith("-")]
        fits = all(t.isupper() or t == w for t, w in zip(tokens, words, strict=False))
        if not fits:
            continue
        if len(words) < len(tokens):
            if not tokens[len(words)].isupper():
                found.append(tokens[len(words)])
        else:
            found += [a.option for a in cmd.args if not a.positional and a.at(where)]
            found += [str(c) for a in cmd.args if a.positional for c in a.choices]
    return found
