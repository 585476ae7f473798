"""The `access` section of a `.lnc` file (docs/configuration.md, docs/security.md): lines
`allow|deny VERB[, VERB...] NAME_PATTERN: CLIENT_PATTERN[, ...]` saying which clients may
publish, subscribe, call, provide or set what.  The first line (in file order) whose verb,
name and client match decides; what no line matches is allowed."""

from __future__ import annotations

import re
from typing import TYPE_CHECKING

from .drafts import KeyLine
from .errors import LineError, did_you_mean, shift
from .model import ACCESS_VERBS, AccessRule, Location
from .sections import Section
from .text import split_value, unquote

if TYPE_CHECKING:
    from .parser import Parser

ACTIONS = ("allow", "deny")
# Names of topics, services, parameter blocks and clients, and the fnmatch characters.
_PATTERN_RE = re.compile(r"[A-Za-z0-9_.:/\-*?\[\]!]+\Z")
_WORD_RE = re.compile(r'"(?:[^"\\]|\\.)*"|[^\s,]+')  # a quoted name may hold a colon


def _pattern_problem(pattern: str, what: str) -> str | None:
    if not _PATTERN_RE.match(pattern):
        return (f"bad {what} pattern '{pattern}' (names may only contain A-Z a-z 0-9 _ . : / "
                "-, patterns also * ? [ ] !)")
    return None


class AccessSection(Section):
    """Receives the key lines of an `access` section."""

    kind = "access"
    general_keys = True

    def key(self, p: Parser, kl: KeyLine) -> None:
        if kl.add:
            raise LineError.at(kl.loc, "'add' has no meaning in the access section")
        text = p.expand_key(kl)
        exact = text == kl.key.strip()
        lead = len(kl.key) - len(kl.key.lstrip())

        def at(offset: int) -> Location:
            return shift(kl.loc, lead + offset) if exact else kl.loc

        words = [(m.group(), m.start()) for m in _WORD_RE.finditer(text)]
        if len(words) < 3 or words[0][0] not in ACTIONS:
            raise LineError.at(at(0), "an access line is 'allow|deny VERB[, VERB...] "
                                      "NAME_PATTERN: CLIENT_PATTERN[, ...]', e.g. 'allow "
                                      "publish arm.command: controller*'"
                                      + (did_you_mean(words[0][0], ACTIONS) if words else ""))
        verbs: set[str] = set()
        for verb, offset in words[1:-1]:
            if verb == "*":
                verbs.update(ACCESS_VERBS)
            elif verb in ACCESS_VERBS:
                verbs.add(verb)
            else:
                raise LineError.at(at(offset), f"unknown access verb '{verb}' (one of "
                                               f"{', '.join(ACCESS_VERBS)} or *)"
                                               f"{did_you_mean(verb, ACCESS_VERBS)}")
        pattern, offset = words[-1]
        pattern = unquote(pattern)[0]
        problem = _pattern_problem(pattern, "name")
        if problem:
            raise LineError.at(at(offset), problem)
        clients = []
        for value in p.values(kl):
            for item in split_value(value, ", "):
                if not item.text:
                    continue
                problem = _pattern_problem(item.text, "client name")
                if problem:
                    raise LineError.at(item.loc, problem)
                clients.append(item.text)
        if not clients:
            values = p.values(kl)
            raise LineError.at(values[0].loc if values else kl.loc,
                               "an access line needs the clients it is about after the "
                               "colon, e.g. 'controller*' or '*' for every client")
        p.drafts.access_rules.append(AccessRule(words[0][0] == "allow", frozenset(verbs),
                                                pattern, tuple(clients), kl.loc))
