"""Events across languages: Python calls reach C and C++ handlers with every field (the
dynamic text included, with non-ASCII and JSON-hostile characters), C and C++ calls reach
Python handlers, replies come back typed, and callers filter by the connect struct."""

from __future__ import annotations

from typing import Any

import links_and_nodes as ln

from .conftest import FAULT, LIMIT, Manager, c_call, next_call, serving, start_handler

TEXT = 'over temperature \u00e9 "joint 3" \\ ,'


def test_python_calls_c_handlers(manager: Manager) -> None:
    loud = start_handler(manager, "py2c.faults", "--min-severity", "2", "--reply", "--name", "a")
    quiet = start_handler(manager, "py2c.faults", "--min-severity", "5", "--name", "b")
    with manager.client("caller") as clnt:
        ev = clnt.get_event("py2c.faults", FAULT)
        assert ev.call(severity=3, code=-7, text=TEXT, timeout=LIMIT) == 2
        for proc in (loud, quiet):
            assert next_call(proc) == {"event": "py2c.faults", "severity": 3, "code": -7,
                                       "text": TEXT}
        a, b = ev.results  # by handler name: a's before b's
        assert (a.client, b.client) == ("a", "b")
        assert a.handler.startswith("ln_event/py2c.faults/a.")
        assert (a.ok, b.ok, a.error_name, a.error) == (True, True, "OK", "")
        assert (a.connect.min_severity, b.connect.min_severity) == (2, 5)
        # the C handler reverses the bytes: undecodable UTF-8 comes back as surrogate escapes
        backwards = TEXT.encode()[::-1].decode("utf-8", "surrogateescape")
        assert a.reply.to_dict() == {"severity": 4, "code": -14, "text": backwards}
        assert b.reply is None
        # a call struct works as well as keyword fields, and empty text too
        data = ev.call_class.from_dict({"severity": 1, "code": 0})
        assert ev.call(data, timeout=LIMIT) == 2
        assert next_call(loud)["text"] == "" and next_call(quiet)["severity"] == 1


def test_c_calls_python_handler(manager: Manager) -> None:
    seen: list[dict[str, Any]] = []

    def on_fault(call: Any) -> dict[str, Any]:
        seen.append(call.to_dict())
        return {"severity": call.severity * 10, "text": call.text.upper()}

    with manager.client("handler") as clnt:
        h = clnt.connect_event("c2py.faults", FAULT, on_fault, min_severity=4)
        assert h.service_name.startswith("ln_event/c2py.faults/handler.")
        with serving(clnt) as counts:
            code, got = c_call(manager, "c2py.faults", "--severity", "6", "--code", "12",
                               "--text", "hot \u00fc")
        assert sum(counts) == 1
    assert code == 0 and got == {"delivered": 1, "results": [{
        "handler": h.service_name, "client": "handler", "code": "OK", "error": "",
        "min_severity": 4, "reply": {"severity": 60, "code": 0, "text": "HOT \u00dc"}}]}
    assert seen == [{"severity": 6, "code": 12, "text": "hot \u00fc"}]


def test_python_handler_without_reply_and_with_error(manager: Manager) -> None:
    def quiet(call: Any) -> None:
        return None

    def refusing(call: Any) -> None:
        raise ValueError(f"code {call.code} is not mine")

    with manager.client("handlers") as clnt:
        clnt.connect_event("c2py.mixed", FAULT, quiet, min_severity=1)
        clnt.connect_event("c2py.mixed", FAULT, refusing, min_severity=2)
        with serving(clnt):
            code, got = c_call(manager, "c2py.mixed", "--code", "9")
    assert code == 0 and got["delivered"] == 1
    ok, failed = sorted(got["results"], key=lambda r: r["min_severity"])
    assert (ok["code"], ok["reply"]) == ("OK", None)
    assert failed["code"] == "ESERVICE" and "ValueError: code 9 is not mine" in failed["error"]


def test_filters_by_connect_struct(manager: Manager) -> None:
    procs = {n: start_handler(manager, "filter.faults", "--min-severity", str(n), "--name",
                              f"h{n}") for n in (1, 3, 5)}
    with manager.client("caller") as clnt:
        ev = clnt.get_event("filter.faults", FAULT)
        ev.filter = lambda connect: connect.min_severity <= 3
        assert ev.call(severity=3, timeout=LIMIT) == 2
        assert [r.client for r in ev.results] == ["h1", "h3"]
        ev.filter = None
        assert ev.call(severity=0, timeout=LIMIT) == 3
    assert [next_call(procs[1])["severity"], next_call(procs[1])["severity"]] == [3, 0]
    assert next_call(procs[5])["severity"] == 0
    code, got = c_call(manager, "filter.faults", "--severity", "1", "--filter")
    assert code == 0 and [r["client"] for r in got["results"]] == ["h1"]


def test_filter_exception_stops_the_call(manager: Manager) -> None:
    proc = start_handler(manager, "filter.raise", "--name", "only")
    with manager.client("caller") as clnt:
        ev = clnt.get_event("filter.raise", FAULT)

        def broken(connect: Any) -> bool:
            raise RuntimeError("filter broke")

        ev.filter = broken
        try:
            ev.call(code=1, timeout=LIMIT)
        except RuntimeError as exc:
            assert str(exc) == "filter broke"
        else:
            raise AssertionError("the filter's exception was not raised")
        assert ev.results == []
        ev.filter = None
        assert ev.call(code=2, timeout=LIMIT) == 1
    assert next_call(proc)["code"] == 2  # the stopped call never reached it


def test_cpp_handler_and_caller(manager: Manager) -> None:
    proc = start_handler(manager, "cpp.faults", "0", "2", cpp=True)
    with manager.client("py") as clnt:
        assert clnt.call_event("cpp.faults", FAULT, severity=2, code=5, text="abc",
                               timeout=LIMIT) == 1
        assert next_call(proc) == {"event": "cpp.faults", "severity": 2, "code": 5,
                                   "text": "abc"}
        ev = clnt.get_event("cpp.faults", FAULT)
        assert ev.call(code=-1, timeout=LIMIT) == 0  # the C++ handler throws for -1
        assert ev.results[0].error_name == "ESERVICE"
        assert "negative code" in ev.results[0].error

        def reply(call: Any) -> Any:
            return ev.call_class.from_dict({"severity": call.severity, "code": call.code + 1,
                                            "text": "py"})

        clnt.connect_event("cpp.calls", FAULT, reply, min_severity=1)
        with serving(clnt):
            code, got = c_call(manager, "cpp.calls", "1", "41", "xyz", cpp=True)
    assert code == 0 and got == {"delivered": 1, "replies": ["py"], "codes": ["OK"]}
    assert proc.wait(LIMIT) == 0


def test_dict_and_struct_connect(manager: Manager) -> None:
    with manager.client("handlers") as clnt:
        cls = ln.message_class(FAULT)
        connect_class = dict((n, e) for n, _k, e, _c in cls._ln_specs_)["connect"]
        a = clnt.connect_event("forms.faults", FAULT, lambda c: None, {"min_severity": 7})
        b = clnt.connect_event("forms.faults", FAULT, lambda c: None,
                               connect_class.from_dict({"min_severity": 8}))
        assert (a.connect.min_severity, b.connect.min_severity) == (7, 8)
        listed = clnt.control("events", name="forms.faults")["events"]
        assert [e["name"] for e in listed] == ["forms.faults"]
        assert sorted(h["connect"] for h in listed[0]["handlers"]) == ["07000000", "08000000"]
