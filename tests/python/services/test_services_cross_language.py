"""Services across languages: the C service_tool (tests/c/tools) provides robot/plan_path and
robot/set_gains to Python callers, and calls Python providers.  Both sides compute the
response by the same rule (conftest.plan), so every field is compared exactly."""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from typing import Any

import pytest

import links_and_nodes as ln

from .conftest import GOAL, LIMIT, Manager, c_call, plan, plan_path_handler, serving, start_provider

CONSTRAINTS = ["joint_limits", "tcp \u00e9 \"quoted\" \\ ", "", "collision,self"]


def plan_args(goal: list[float], max_velocity: float, constraints: list[str]) -> list[str]:
    args = ["--goal", ",".join(repr(g) for g in goal), "--max-velocity", repr(max_velocity)]
    for c in constraints:
        args += ["--constraint", c]
    return args


def test_c_provider_python_caller(manager: Manager) -> None:
    start_provider(manager, "c.plan")
    with manager.client("caller") as clnt:
        svc = clnt.get_service("c.plan", "robot/plan_path")
        for constraints in (CONSTRAINTS, [], ["only"]):
            svc.req.goal = GOAL
            svc.req.max_velocity = 1 / 3
            svc.req.constraints = [{"data": c} for c in constraints]
            assert svc.call(timeout=LIMIT).to_dict() == plan(GOAL, 1 / 3, constraints)


def test_c_set_gains_provider_python_caller(manager: Manager) -> None:
    start_provider(manager, "c.gains", "--md", "robot/set_gains")
    with manager.client("caller") as clnt:
        svc = clnt.get_service("c.gains", "robot/set_gains")
        svc.req.kp = [0.5 * j for j in range(7)]
        svc.req.kd = [0.25] * 7
        svc.req.profile_name = "soft \u00fc"
        assert svc.call(timeout=LIMIT).to_dict() == {
            "ok": 1, "message": "soft \u00fc: kp sum 10.5, kd sum 1.75"}


def test_c_provider_error_reaches_python(manager: Manager) -> None:
    start_provider(manager, "c.plan")
    with manager.client("caller") as clnt:
        svc = clnt.get_service("c.plan", "robot/plan_path")
        svc.req.constraints = [{"data": "a"}, {"data": "b"}, {"data": "fail"}]
        with pytest.raises(ln.LnServiceError, match="constraint 2 is 'fail'"):
            svc.call(timeout=LIMIT)
        svc.req.constraints = [{"data": "a"}]  # the provider keeps serving
        assert svc.call(timeout=LIMIT).message == "a"


def test_c_provider_in_a_pool_with_parallel_python_callers(manager: Manager) -> None:
    start_provider(manager, "c.plan", "--pool", "3")
    with manager.client("callers") as clnt:
        handles = [clnt.get_service("c.plan", "robot/plan_path") for _ in range(6)]
        for i, svc in enumerate(handles):
            svc.req.goal = [float(i)] * 7
            svc.req.constraints = [{"data": f"caller {i}"}] * (i + 1)

        def calls(svc: ln.service) -> list[dict[str, Any]]:
            return [svc.call(timeout=LIMIT).to_dict() for _ in range(20)]

        with ThreadPoolExecutor(len(handles)) as pool:
            results = list(pool.map(calls, handles))
    for i, got in enumerate(results):
        assert got == [plan([float(i)] * 7, 0.0, [f"caller {i}"] * (i + 1))] * 20


def test_python_provider_c_caller(manager: Manager) -> None:
    with manager.client("provider") as clnt:
        clnt.get_service_provider("py.plan", "robot/plan_path", plan_path_handler)
        with serving(clnt) as counts:
            for constraints in (CONSTRAINTS, [], ["x"]):
                code, got = c_call(manager, "py.plan", *plan_args(GOAL, 0.75, constraints))
                assert code == 0 and got == plan(GOAL, 0.75, constraints)
        assert sum(counts) == 3


def test_python_set_gains_provider_c_caller(manager: Manager) -> None:
    seen: list[dict[str, Any]] = []

    def handler(request: ln.service_request) -> None:
        seen.append(request.req.to_dict())
        request.respond({"ok": 7, "message": request.req.profile_name[::-1]})

    with manager.client("provider") as clnt:
        clnt.get_service_provider("py.gains", "robot/set_gains", handler)
        with serving(clnt):
            code, got = c_call(manager, "py.gains", "--md", "robot/set_gains",
                               "--kp", ",".join(repr(g) for g in GOAL), "--kd", "1,2,3,4,5,6,7",
                               "--profile", "stiff \u00e4")
    assert code == 0 and got == {"ok": 7, "message": "\u00e4 ffits"}
    assert seen == [{"kp": GOAL, "kd": [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0],
                     "profile_name": "stiff \u00e4"}]


def test_python_errors_reach_c(manager: Manager) -> None:
    def handler(request: ln.service_request) -> None:
        constraints = [c.data for c in request.req.constraints]
        if constraints == ["raise"]:
            raise ValueError("no path around \"obstacle\"")
        request.respond_error(f"refused {len(constraints)} constraints")

    with manager.client("provider") as clnt:
        clnt.get_service_provider("py.plan", "robot/plan_path", handler)
        with serving(clnt):
            code, got = c_call(manager, "py.plan", "--constraint", "raise")
            assert code == 1 and got["error"] == "ESERVICE"
            assert "ValueError: no path around \"obstacle\"" in got["text"]
            code, got = c_call(manager, "py.plan", "--constraint", "a", "--constraint", "b")
            assert code == 1 and got["error"] == "ESERVICE"
            assert "refused 2 constraints" in got["text"]


def test_layout_mismatch_across_languages(manager: Manager) -> None:
    start_provider(manager, "c.plan")
    with manager.client("mixed") as clnt:
        svc = clnt.get_service("c.plan", "robot/set_gains")
        with pytest.raises(ln.LnLayoutError) as info:
            svc.call(timeout=LIMIT)
        assert "robot/plan_path" in str(info.value) and "robot/set_gains" in str(info.value)

        clnt.get_service_provider("py.plan", "robot/plan_path", plan_path_handler)
        with serving(clnt):
            code, got = c_call(manager, "py.plan", "--md", "robot/set_gains")
        assert code == 1 and got["error"] == "ELAYOUT"
        assert "robot/plan_path" in got["text"] and "robot/set_gains" in got["text"]


def test_c_provider_exits_after_count(manager: Manager) -> None:
    proc = start_provider(manager, "c.plan", "--count", "2")
    with manager.client("caller") as clnt:
        svc = clnt.get_service("c.plan", "robot/plan_path")
        assert svc.call(timeout=LIMIT).status == 0
        assert svc.call(timeout=LIMIT).status == 0
        assert proc.wait(timeout=LIMIT) == 0
        with pytest.raises((ln.LnConnectionError, ln.LnNotfoundError)):
            svc.call(timeout=LIMIT)
