"""The `access` section (docs/security.md, "Access rules"): its grammar with errors at
file:line:col and first-match-wins with everything allowed that no line matches
(test_access_live.py: a live manager applying them)."""

from __future__ import annotations

from pathlib import Path

import pytest

from links_and_nodes.manager.config import ConfigError, load
from links_and_nodes.manager.registry.access import Access
from links_and_nodes.manager.registry.model import RequestError
from links_and_nodes.tools import protocol as p

RULES = """\
allow publish arm.command: controller*, planner
deny publish arm.*: *
allow subscribe, call sensors.*: *
deny call, provide *: guest*
deny set *.gains: *
"""


def _load(tmp_path: Path, access: str) -> Access:
    path = tmp_path / "a.lnc"
    path.write_text(f"instance\nname: acc\nmanager: :12345\n\naccess\n{access}")
    return Access(load(path).access_rules)


def _allowed(access: Access, client: str, msg: p.Message) -> bool:
    try:
        access.check(client, msg)
    except RequestError as exc:
        assert exc.code == "EPERM"
        return False
    return True


def _publish(topic: str) -> p.Message:
    return p.Publish(1, topic, "m", 0, 8, 1, 0)


def _find(name: str) -> p.Message:
    return p.FindService(1, name, "m", 0)


def test_parsed_rules(tmp_path: Path) -> None:
    rules = _load(tmp_path, RULES).rules
    assert [(r.allow, sorted(r.verbs), r.pattern, r.clients) for r in rules] == [
        (True, ["publish"], "arm.command", ("controller*", "planner")),
        (False, ["publish"], "arm.*", ("*",)),
        (True, ["call", "subscribe"], "sensors.*", ("*",)),
        (False, ["call", "provide"], "*", ("guest*",)),
        (False, ["set"], "*.gains", ("*",)),
    ]
    assert str(rules[0].location).endswith("a.lnc:6:1")


@pytest.mark.parametrize(("client", "msg", "allowed"), [
    ("controller-1", _publish("arm.command"), True),     # line 1
    ("planner", _publish("arm.command"), True),          # line 1
    ("guest", _publish("arm.command"), False),           # line 2: first match decides
    ("controller-1", _publish("arm.state"), False),      # line 2
    ("guest", _publish("camera.image"), True),           # no line: allowed
    ("guest", p.Subscribe(1, "arm.state", "m", 0, 8, 1, 0), True),
    ("guest", _find("sensors.reset"), True),             # line 3 before line 4
    ("guest", _find("robot.stop"), False),               # line 4
    ("planner", _find("robot.stop"), True),              # no line
    ("guest", p.RegisterService(1, "x.y", "m", 0, "a|b", "", "", "", "", 0), False),
    ("tool", _find("arm.controller.parameters.gains"), False),   # set arm.controller.gains
    ("tool", _find("arm.controller.parameters.limits"), True),
    ("guest", p.ReclaimPort(1, p.RECLAIM_PUBLISHER, "arm.command", "m", 0, 8, 1, 0, "s",
                            p.NO_READER), False),
])
def test_first_match_wins(tmp_path: Path, client: str, msg: p.Message, allowed: bool) -> None:
    assert _allowed(_load(tmp_path, RULES), client, msg) is allowed


@pytest.mark.parametrize(("line", "where", "message"), [
    ("allow publsh x: y", "6:7", "unknown access verb 'publsh'"),
    ("permit publish x: y", "6:1", "an access line is 'allow|deny VERB"),
    ("allow publish x%y: c", "6:15", "bad name pattern 'x%y'"),
    ("allow publish x: c d$", "6:20", "bad client name pattern 'd$'"),
    ("allow publish x:", "6:", "needs the clients it is about"),
])
def test_errors_have_file_line_col(tmp_path: Path, line: str, where: str,
                                   message: str) -> None:
    with pytest.raises(ConfigError) as info:
        _load(tmp_path, line + "\n")
    assert f"a.lnc:{where}" in str(info.value)
    assert message in str(info.value)
