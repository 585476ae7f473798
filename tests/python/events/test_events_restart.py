"""Events across a manager restart: handlers in C and Python register their service and
their connect struct again by themselves, and calls reach them afterwards, from a caller
made before the restart and from a new one."""

from __future__ import annotations

from polling import wait_for

from .conftest import FAULT, LIMIT, Restarts, serving


def test_handlers_come_back_after_a_restart(restarts: Restarts) -> None:
    restarts.tool("event_tool", "connect", "rs.faults", "--min-severity", "3", "--reply",
                  "--name", "c_handler")
    seen: list[int] = []
    handler_client = restarts.client("py_handler")
    handler_client.connect_event("rs.faults", FAULT, lambda c: seen.append(c.code),
                                 min_severity=1)
    caller = restarts.client("caller")

    def listed() -> list[tuple[str, str]]:
        with restarts.control() as mgr:
            events = mgr.command("events", name="rs.faults")["events"]
        return sorted((h["client"], h["connect"]) for e in events for h in e["handlers"])

    with serving(handler_client):
        ev = caller.get_event("rs.faults", FAULT)
        assert ev.call(code=1, timeout=LIMIT) == 2
        before = listed()
        assert before == [("c_handler", "03000000"), ("py_handler", "01000000")]
        restarts.restart()
        wait_for(lambda: listed() == before, "both handlers connected again")
        assert ev.call(code=2, timeout=LIMIT) == 2
        assert restarts.client("late").call_event("rs.faults", FAULT, code=3,
                                                  timeout=LIMIT) == 2
        assert [r.reply.code if r.reply else None for r in ev.results] == [4, None]
    assert seen == [1, 2, 3]
