"""Which topics a command takes: --topic NAME, --regex RE (whole name), --exclude RE."""

from __future__ import annotations

import argparse
import re


def add_selection_args(ap: argparse.ArgumentParser) -> None:
    ap.add_argument("-t", "--topic", action="append", default=[], metavar="T",
                    help="this topic (may be repeated)")
    ap.add_argument("-e", "--regex", action="append", default=[], type=_regex, metavar="RE",
                    help="topics whose whole name matches RE (may be repeated)")
    ap.add_argument("-x", "--exclude", action="append", default=[], type=_regex,
                    metavar="RE", help="not the topics whose whole name matches RE "
                    "(may be repeated)")


def _regex(text: str) -> re.Pattern[str]:
    try:
        return re.compile(text)
    except re.error as exc:
        raise argparse.ArgumentTypeError(f"{text!r}: {exc}") from None


class Selection:
    """--topic/--regex name what is taken (all when neither is given); --exclude removes."""

    def __init__(self, args: argparse.Namespace) -> None:
        self.names = set(args.topic)
        self.regexes: list[re.Pattern[str]] = args.regex
        self.excludes: list[re.Pattern[str]] = args.exclude
        self._decided: dict[str, bool] = {}

    def __call__(self, topic: str) -> bool:
        wanted = self._decided.get(topic)
        if wanted is None:
            wanted = self._decided[topic] = self._decide(topic)
        return wanted

    def _decide(self, topic: str) -> bool:
        named = not (self.names or self.regexes) or topic in self.names or any(
            r.fullmatch(topic) for r in self.regexes)
        return named and not any(r.fullmatch(topic) for r in self.excludes)
