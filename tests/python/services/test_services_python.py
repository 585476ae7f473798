"""Python callers and Python providers: requests and responses arrive field for field,
responses stay valid after the call, errors arrive as the exception classes of libln's
table with their text."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

import links_and_nodes as ln

from .conftest import GOAL, LIMIT, Manager, plan, plan_path_handler, serving


def test_set_gains_round_trip(manager: Manager) -> None:
    seen: list[dict[str, Any]] = []

    def handler(request: ln.service_request) -> None:
        seen.append(request.req.to_dict())
        assert request.service_name == "robot.set_gains"
        request.resp.ok = 1
        request.resp.message = f"{request.req.profile_name}|{float(request.req.kd[6])!r}"
        request.respond()

    with manager.client("provider") as prov_c, manager.client("caller") as call_c:
        prov_c.get_service_provider("robot.set_gains", "robot/set_gains", handler)
        svc = call_c.get_service("robot.set_gains", "robot/set_gains")
        svc.req.kp = np.arange(7) * 1.5
        svc.req.kd = [1 / 3] * 7
        svc.req.profile_name = "soft \u00fc"
        with serving(prov_c) as counts:
            resp = svc.call(timeout=LIMIT)
        assert resp is svc.resp
        assert resp.to_dict() == {"ok": 1, "message": f"soft \u00fc|{1 / 3!r}"}
        assert seen == [{"kp": [1.5 * j for j in range(7)], "kd": [1 / 3] * 7,
                         "profile_name": "soft \u00fc"}]
        assert sum(counts) == 1


def test_plan_path_strings_and_nested_structs(manager: Manager) -> None:
    with manager.client("provider") as prov_c, manager.client("caller") as call_c:
        prov_c.get_service_provider("robot.plan", "robot/plan_path", plan_path_handler)
        svc = call_c.get_service("robot.plan", "robot/plan_path")
        with serving(prov_c):
            for constraints in (["joint_limits", "tcp \u00e9", "", "collision"], [], ["x"]):
                svc.req.goal = GOAL
                svc.req.max_velocity = 0.75
                svc.req.constraints = [{"data": c} for c in constraints]
                assert svc.call(timeout=LIMIT).to_dict() == plan(GOAL, 0.75, constraints)


def test_deeply_nested_dynamic_fields(manager: Manager) -> None:
    """lntest/query: dynamic arrays of structs holding dynamic arrays, in both directions."""
    def inner(a: int) -> dict[str, Any]:
        return {"a": a, "b": [a * 0.5, -a * 0.25], "tag": f"t{a}"}

    def middle(k: int) -> dict[str, Any]:
        return {"flag": k, "one": inner(k), "many": [inner(k + 1), inner(k + 2), inner(k + 3)],
                "dyn": [inner(10 * k + i) for i in range(k)]}

    def answer(request: ln.service_request) -> None:
        q = request.req.to_dict()
        request.respond({
            "result": {"m": q["filters"][0], "ms": q["filters"][:2], "ds": q["filters"],
                       "note": ",".join(k["data"] for k in q["keys"]), "tail": q["mode"] / 4},
            "best": [q["filters"][1], q["filters"][0]],
        })

    filters = [middle(k) for k in range(1, 4)]
    keys = ["alpha", "\u03b2eta", ""]
    with manager.client("provider") as prov_c, manager.client("caller") as call_c:
        prov_c.get_service_provider("db.query", "lntest/query", answer)
        svc = call_c.get_service("db.query", "lntest/query")
        svc.req.update({"filters": filters, "keys": [{"data": k} for k in keys], "mode": 6})
        with serving(prov_c):
            got = svc.call(timeout=LIMIT).to_dict()
        expected = svc.response_class.from_dict({
            "result": {"m": filters[0], "ms": filters[:2], "ds": filters,
                       "note": ",".join(keys), "tail": 1.5},
            "best": [filters[1], filters[0]],
        }).to_dict()
        assert got == expected
        assert got["result"]["ds"][2]["dyn"][1] == inner(31)


def test_response_stays_valid_after_next_call_and_close(manager: Manager) -> None:
    with manager.client("provider") as prov_c, manager.client("caller") as call_c:
        prov_c.get_service_provider("robot.plan", "robot/plan_path", plan_path_handler)
        svc = call_c.get_service("robot.plan", "robot/plan_path")
        svc.req.goal = GOAL
        with serving(prov_c):
            svc.req.constraints = [{"data": c} for c in ("a", "bb", "ccc")]
            first = svc.call(timeout=LIMIT)
            waypoints = first.waypoints
            position = waypoints[2].position
            velocity = first.waypoints[1].velocity
            svc.req.constraints = [{"data": "zzzz"}]
            svc.req.max_velocity = 9.0
            second = svc.call(timeout=LIMIT).to_dict()
        assert second == plan(GOAL, 9.0, ["zzzz"])
        assert [w.cycle for w in waypoints] == [0, 1, 2]
        assert position.tolist() == [g + 2 for g in GOAL]
        assert velocity.tolist() == [0.0] * 7
        svc.close()
    # the client, the provider and libln's memory are gone; what was read stays
    assert svc.resp.to_dict() == second
    assert position.tolist() == [g + 2 for g in GOAL]
    with pytest.raises(ValueError, match="closed"):
        svc.call()


def test_failed_call_leaves_response_as_it_was(manager: Manager) -> None:
    with manager.client("provider") as prov_c, manager.client("caller") as call_c:
        prov_c.get_service_provider("robot.plan", "robot/plan_path", plan_path_handler)
        svc = call_c.get_service("robot.plan", "robot/plan_path")
        with serving(prov_c):
            svc.req.constraints = [{"data": "ok"}]
            before = svc.call(timeout=LIMIT).to_dict()
            svc.req.constraints = [{"data": "ok"}, {"data": "fail"}]
            with pytest.raises(ln.LnServiceError, match="constraint 1 is 'fail'"):
                svc.call(timeout=LIMIT)
        assert svc.resp.to_dict() == before


def test_handler_errors_arrive_as_service_errors(manager: Manager) -> None:
    def handler(request: ln.service_request) -> None:
        mode = request.req.profile_name
        if mode == "raise":
            raise ValueError("bad gains \u00e4")
        if mode == "error":
            request.respond_error("controller busy")
        elif mode == "silent":
            pass
        elif mode == "raise after respond":
            request.respond({"ok": 1, "message": "answered"})
            raise RuntimeError("too late")
        else:
            request.respond({"ok": 1, "message": mode})

    with manager.client("provider") as prov_c, manager.client("caller") as call_c:
        prov_c.get_service_provider("robot.set_gains", "robot/set_gains", handler)
        svc = call_c.get_service("robot.set_gains", "robot/set_gains")
        with serving(prov_c):
            cases = [("raise", "ValueError: bad gains \u00e4"), ("error", "controller busy"),
                     ("silent", "returned without responding")]
            for mode, text in cases:
                svc.req.profile_name = mode
                with pytest.raises(ln.LnServiceError) as info:
                    svc.call(timeout=LIMIT)
                assert text in str(info.value)
                assert info.value.code == ln.LnServiceError.code
            # the provider keeps serving, and an answer given before an exception counts
            svc.req.profile_name = "raise after respond"
            assert svc.call(timeout=LIMIT).to_dict() == {"ok": 1, "message": "answered"}
            svc.req.profile_name = "fine"
            assert svc.call(timeout=LIMIT).to_dict() == {"ok": 1, "message": "fine"}


def test_request_is_kept_but_cannot_be_answered_later(manager: Manager) -> None:
    kept: list[ln.service_request] = []

    def handler(request: ln.service_request) -> None:
        kept.append(request)
        request.respond({"values": request.req.values * request.req.factor})

    with manager.client("provider") as prov_c, manager.client("caller") as call_c:
        prov_c.get_service_provider("math.scale", "lntest/scale", handler)
        svc = call_c.get_service("math.scale", "lntest/scale")
        svc.req.values = [1.0, -2.0, 3.5]
        svc.req.factor = 2.0
        with serving(prov_c):
            assert svc.call(timeout=LIMIT).values.tolist() == [2.0, -4.0, 7.0]
            svc.req.values = np.arange(5.0)
            assert svc.call(timeout=LIMIT).values.tolist() == [0.0, 2.0, 4.0, 6.0, 8.0]
        assert kept[0].req.values.tolist() == [1.0, -2.0, 3.5]  # its own copy
        with pytest.raises(ValueError, match="inside its handler"):
            kept[0].respond()


def test_empty_sections_and_empty_dynamic_fields(manager: Manager) -> None:
    def scale(request: ln.service_request) -> None:
        request.respond({"values": request.req.values * request.req.factor})

    with manager.client("provider") as prov_c, manager.client("caller") as call_c:
        prov_c.get_service_provider("nop", "lntest/ping", lambda request: request.respond())
        prov_c.get_service_provider("math.scale", "lntest/scale", scale)
        ping = call_c.get_service("nop", "lntest/ping")
        svc = call_c.get_service("math.scale", "lntest/scale")
        with serving(prov_c):
            assert ping.call(timeout=LIMIT).to_dict() == {}
            assert svc.call(timeout=LIMIT).values.tolist() == []  # NULL pointer, length 0
            svc.req.values = []
            assert svc.call(timeout=LIMIT).to_dict() == {"values": []}


def test_not_provided_and_not_a_service(manager: Manager) -> None:
    with manager.client("caller") as clnt:
        svc = clnt.get_service("nobody.provides.this", "robot/set_gains")
        with pytest.raises(ln.LnNotfoundError, match="nobody.provides.this"):
            svc.call(timeout=LIMIT)
        with pytest.raises(ln.LnMdError, match="robot/joint_state"):
            clnt.get_service("robot.state", "robot/joint_state")


def test_another_layout_is_refused_naming_both_mds(manager: Manager) -> None:
    with manager.client("provider") as prov_c, manager.client("caller") as call_c:
        prov_c.get_service_provider("robot.plan", "robot/plan_path", plan_path_handler)
        svc = call_c.get_service("robot.plan", "robot/set_gains")
        with serving(prov_c), pytest.raises(ln.LnLayoutError) as info:
            svc.call(timeout=LIMIT)
        assert "robot/plan_path" in str(info.value)
        assert "robot/set_gains" in str(info.value)


def test_timeout_then_the_next_call_starts_afresh(manager: Manager) -> None:
    with manager.client("provider") as prov_c, manager.client("caller") as call_c:
        prov_c.get_service_provider("robot.plan", "robot/plan_path", plan_path_handler)
        svc = call_c.get_service("robot.plan", "robot/plan_path")
        svc.req.constraints = [{"data": "late"}]
        with pytest.raises(ln.LnTimeoutError):  # nobody handles the provider's requests yet
            svc.call(timeout=0.2)
        with serving(prov_c):
            assert svc.call(timeout=LIMIT).to_dict() == plan([0.0] * 7, 0.0, ["late"])


def test_wait_and_handle_counts_and_errors(manager: Manager) -> None:
    with manager.client("provider") as clnt:
        with pytest.raises(ln.LnNotfoundError):
            clnt.wait_and_handle_service_group_requests("no_such_group", timeout=0)
        clnt.get_service_provider("robot.plan", "robot/plan_path", plan_path_handler,
                                  group="planning")
        assert clnt.wait_and_handle_service_group_requests("planning", timeout=0) == 0
        with pytest.raises(ln.LnNotfoundError):  # it is not in the default group
            clnt.wait_and_handle_service_group_requests(timeout=0)


def test_unregister_and_client_close(manager: Manager) -> None:
    with manager.client("caller") as call_c:
        svc = call_c.get_service("robot.plan", "robot/plan_path")
        prov_c = manager.client("provider")
        provider = prov_c.get_service_provider("robot.plan", "robot/plan_path",
                                               plan_path_handler)
        with serving(prov_c):
            assert svc.call(timeout=LIMIT).status == 0
        provider.close()
        provider.close()  # idempotent
        with pytest.raises((ln.LnNotfoundError, ln.LnConnectionError)):
            svc.call(timeout=LIMIT)
        # the name is free again: another provider of this client takes it
        prov_c.get_service_provider("robot.plan", "robot/plan_path", plan_path_handler)
        svc.req.constraints = [{"data": "again"}]
        with serving(prov_c):
            assert svc.call(timeout=LIMIT).message == "again"
        prov_c.close()  # unregisters what it provides
        for _ in range(2):  # the connection is lost, and a fresh lookup finds nobody
            with pytest.raises((ln.LnNotfoundError, ln.LnConnectionError)):
                svc.call(timeout=LIMIT)
    with pytest.raises(ValueError, match="closed"):
        svc.call()
    svc.close()  # closing after the client is harmless


def test_maximum_sizes(manager: Manager) -> None:
    def answer(request: ln.service_request) -> None:
        request.respond({"values": [2.0] * int(request.req.factor)})

    with manager.client("provider") as prov_c, manager.client("caller") as call_c:
        prov_c.get_service_provider("math.scale", "lntest/scale", answer, max_size=1000)
        svc = call_c.get_service("math.scale", "lntest/scale")
        with serving(prov_c):
            svc.req.values = [1.0] * 200  # 1,600 bytes of request data
            with pytest.raises(ln.LnToobigError, match="provider's maximum of 1000"):
                svc.call(timeout=LIMIT)
            svc.req.values = [1.0] * 10
            svc.req.factor = 100  # 800 bytes of response data
            svc.set_max_size(500)
            with pytest.raises(ln.LnToobigError, match="ln_service_set_max_size"):
                svc.call(timeout=LIMIT)
            svc.req.factor = 3  # both sides go on
            assert svc.call(timeout=LIMIT).values.tolist() == [2.0] * 3
