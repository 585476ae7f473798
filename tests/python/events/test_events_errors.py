"""Bad input to events gives a clear error, in Python and in C: an unknown md, an md that is
not an event, a field the md does not have, a layout that differs from the handlers' (for a
caller and for a second handler), a bad event name, an oversized connect struct, and
nonsense commands to the manager."""

from __future__ import annotations

import math
from typing import Any

import pytest

import links_and_nodes as ln
from ln_generate import MdError

from .conftest import FAULT, LIMIT, Manager, c_call, serving, start_handler


def nothing(call: Any) -> None:
    return None


def test_unknown_and_wrong_kind_of_md(manager: Manager) -> None:
    with manager.client("bad") as clnt:
        with pytest.raises(MdError, match="no/such_event"):
            clnt.get_event("x.y", "no/such_event")
        with pytest.raises(MdError, match="no/such_event"):
            clnt.connect_event("x.y", "no/such_event", nothing)
        with pytest.raises(ln.LnMdError, match="'robot/set_gains' is not an event definition"):
            clnt.call_event("x.y", "robot/set_gains", timeout=LIMIT)
        with pytest.raises(ln.LnMdError, match="not an event definition"):
            clnt.connect_event("x.y", "robot/joint_state", nothing)


def test_fields_the_md_does_not_have(manager: Manager) -> None:
    with manager.client("bad") as clnt:
        ev = clnt.get_event("fields.faults", FAULT)
        with pytest.raises(TypeError, match=r"no field 'sevrity'; its fields: severity, code, "
                                            r"text"):
            ev.call(sevrity=3)
        with pytest.raises(TypeError, match="no field 'min_sev'; its fields: min_severity"):
            clnt.connect_event("fields.faults", FAULT, nothing, min_sev=1)
        with pytest.raises(TypeError, match="a robot_fault_event_call_t struct or a dict"):
            ev.call(42)
        with pytest.raises(ln.LnInvalError, match="timeout is NaN"):
            ev.call(timeout=math.nan)
        assert clnt.control("events")["events"] == []  # nothing got connected


def test_layout_mismatch(manager: Manager) -> None:
    start_handler(manager, "layout.faults", "--name", "faulty")
    with manager.client("other") as clnt:
        with pytest.raises(ln.LnLayoutError, match=r"event \"layout.faults\": layout of md "
                                                   r"\"lntest/alarm_event\" .* differs from "
                                                   r"its handlers' md \"robot/fault_event\""):
            clnt.call_event("layout.faults", "lntest/alarm_event", value=1.0, timeout=LIMIT)
        with pytest.raises(ln.LnLayoutError, match="lntest/alarm_event"):
            clnt.connect_event("layout.faults", "lntest/alarm_event", nothing, level=1)
        # the refused handler left nothing behind: no service, no handler
        assert [s["name"] for s in clnt.control("services")["services"]
                if "/other." in s["name"]] == []
        assert clnt.call_event("layout.faults", FAULT, timeout=LIMIT) == 1
    code, got = c_call(manager, "layout.faults", "--md-hash-off")
    assert code == 1 and got["error"] == "ELAYOUT" and "differs from its handlers' md" in \
        got["text"]


def test_bad_event_names(manager: Manager) -> None:
    with manager.client("bad") as clnt:
        for name in ("", ".hidden", "with space", "x" * 161, "semi;colon"):
            with pytest.raises(ln.LnInvalError, match="event name"):
                clnt.get_event(name, FAULT)
            with pytest.raises(ln.LnInvalError, match="event name"):
                clnt.connect_event(name, FAULT, nothing)


def test_connect_struct_size_limit_and_empty_call(manager: Manager) -> None:
    seen: list[str] = []
    with manager.client("tags") as clnt:
        with pytest.raises(ln.LnToobigError, match="at most 1024 bytes"):
            clnt.connect_event("tags.e", "lntest/tagged_event", nothing, tag="x" * 1100)
        h = clnt.connect_event("tags.e", "lntest/tagged_event",
                               lambda call: seen.append("called"), tag="t" * 1000)
        with serving(clnt):
            ev = clnt.get_event("tags.e", "lntest/tagged_event")
            assert ev.call(timeout=LIMIT) == 1  # a call without fields
            assert ev.results[0].connect.tag == "t" * 1000
            assert ev.results[0].handler == h.service_name
    assert seen == ["called"]


def test_manager_refuses_nonsense(manager: Manager) -> None:
    with manager.client("bad") as clnt:
        with pytest.raises(ln.LnInvalError, match="event name"):
            clnt.control("events", name="bad name")
        with pytest.raises(ln.LnNotfoundError, match="is not registered"):
            clnt.control("event_connect", event="a.b", service="ln_event/a.b/x.1",
                         md_name=FAULT, layout_hash="0x1", signature="|", connect="")
        with pytest.raises(ln.LnInvalError, match="not the name of a handler"):
            clnt.control("event_connect", event="a.b", service="a.b", md_name=FAULT,
                         layout_hash="0x1", signature="|", connect="")
        with pytest.raises(ln.LnInvalError, match="must be hex"):
            clnt.control("event_connect", event="a.b", service="ln_event/a.b/x.1",
                         md_name=FAULT, layout_hash="0x1", signature="|", connect="zz")
