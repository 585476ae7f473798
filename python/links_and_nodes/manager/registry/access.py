"""The `access` rules applied to a client's requests (docs/security.md, "Access rules"):
which verb and name a request stands for, and the first rule (in file order) that matches
it, its verb and the client's name decides; what no rule matches is allowed.  A refusal is
a RequestError EPERM whose text names the rule."""

from __future__ import annotations

from collections.abc import Sequence

from ...tools import protocol as p
from ..config.model import AccessRule
from .model import RequestError

PARAMETERS = ".parameters."  # a parameter block's service: `<client>.parameters.<block>`


def _verb_and_name(msg: p.Message) -> tuple[str, str] | None:
    """What a request asks for, as (verb, name); None for requests no rule governs."""
    if isinstance(msg, p.Publish):
        return "publish", msg.topic
    if isinstance(msg, p.Subscribe):
        return "subscribe", msg.topic
    if isinstance(msg, p.ReclaimPort):
        return ("publish" if msg.kind == p.RECLAIM_PUBLISHER else "subscribe"), msg.topic
    if isinstance(msg, p.RegisterService):
        return "provide", msg.name
    if isinstance(msg, p.FindService):
        owner, sep, block = msg.name.partition(PARAMETERS)
        if sep and owner and block:  # reading and setting go through the block's service
            return "set", f"{owner}.{block}"
        return "call", msg.name
    return None


class Access:
    def __init__(self, rules: Sequence[AccessRule] = ()) -> None:
        self.rules = tuple(rules)

    def check(self, client: str, msg: p.Message) -> None:
        """RequestError EPERM if a rule denies `client` what `msg` asks for."""
        if not self.rules:
            return
        asked = _verb_and_name(msg)
        if asked is None:
            return
        verb, name = asked
        for rule in self.rules:
            if rule.matches(verb, name, client):
                if rule.allow:
                    return
                raise RequestError("EPERM", f"client {client!r} may not {verb} {name!r}: "
                                            f"denied by the access rule at {rule.location}")
