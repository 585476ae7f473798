"""ln.service_provider: service names from the prefix, methods called with the request
fields, and what a method may return."""

from __future__ import annotations

import ctypes
from typing import Any

import numpy as np
import pytest

import links_and_nodes as ln

from .conftest import GOAL, LIMIT, Manager, plan, serving


class robot(ln.service_provider):  # noqa: N801 - written as an LN user would
    def __init__(self, clnt: ln.client, prefix: str) -> None:
        ln.service_provider.__init__(self, clnt, prefix)
        self.arguments: dict[str, dict[str, Any]] = {}
        self.wrap_service_provider("set_gains", "robot/set_gains")
        self.wrap_service_provider("plan_path", "robot/plan_path")
        self.wrap_service_provider("scale", "lntest/scale")
        self.wrap_service_provider("ping", "lntest/ping")
        self.wrap_service_provider("arm.stop", "lntest/ping")  # method arm_stop
        self.wrap_service_provider("misbehave", "robot/set_gains", group="other",
                                   method=self.misbehaving)

    def set_gains(self, kp: np.ndarray, kd: np.ndarray, profile_name: str) -> dict[str, Any]:
        self.arguments["set_gains"] = {"kp": kp, "kd": kd, "profile_name": profile_name}
        return {"ok": 1, "message": f"{profile_name} {float(kp.sum())!r}"}

    def plan_path(self, goal: np.ndarray, max_velocity: float,
                  constraints: Any) -> dict[str, Any]:
        self.arguments["plan_path"] = {"goal": goal, "constraints": constraints}
        result = plan(goal.tolist(), max_velocity, [c.data for c in constraints])
        del result["message"]  # missing fields stay empty
        return result

    def scale(self, values: np.ndarray, factor: float) -> Any:
        return values * factor if factor >= 0 else [-1.0]  # bare value: a numpy array, a list

    def ping(self) -> None:
        self.arguments["ping"] = {}

    def arm_stop(self) -> dict[str, Any]:
        return {}

    def misbehaving(self, kp: np.ndarray, kd: np.ndarray, profile_name: str) -> Any:
        if profile_name == "raise":
            return 1 / 0
        return {"none": None, "bare": 1, "unknown": {"ok": 1, "nonsense": 2}}[profile_name]


@pytest.fixture
def provider(manager: Manager) -> Any:
    with manager.client("wrapper") as clnt:
        prov = robot(clnt, "arm")
        with serving(clnt), serving(clnt, "other"):
            yield prov


def test_names_come_from_the_prefix(manager: Manager, provider: robot) -> None:
    assert sorted(provider.provided_services) == [
        "arm.arm.stop", "arm.misbehave", "arm.ping", "arm.plan_path", "arm.scale",
        "arm.set_gains"]
    with manager.client("caller") as clnt:
        assert clnt.get_service("arm.arm.stop", "lntest/ping").call(LIMIT).to_dict() == {}
        with pytest.raises(ln.LnNotfoundError):
            clnt.get_service("set_gains", "robot/set_gains").call(LIMIT)


def test_no_prefix(manager: Manager) -> None:
    with manager.client("wrapper") as clnt, manager.client("caller") as call_c:
        class pinger(ln.service_provider):  # noqa: N801
            def ping(self) -> None:
                return None

        prov = pinger(clnt)
        prov.wrap_service_provider("ping", "lntest/ping")
        with serving(clnt):
            assert call_c.get_service("ping", "lntest/ping").call(LIMIT).to_dict() == {}
        prov.close()
        assert prov.provided_services == {}


def test_request_fields_arrive_as_keywords(manager: Manager, provider: robot) -> None:
    with manager.client("caller") as clnt:
        gains = clnt.get_service("arm.set_gains", "robot/set_gains")
        gains.req.kp = [0.5 * j for j in range(7)]
        gains.req.profile_name = "stiff"
        assert gains.call(LIMIT).to_dict() == {"ok": 1, "message": "stiff 10.5"}
        args = provider.arguments["set_gains"]
        assert isinstance(args["kp"], np.ndarray) and args["kp"].tolist() == gains.req.kp.tolist()
        assert args["profile_name"] == "stiff"

        svc = clnt.get_service("arm.plan_path", "robot/plan_path")
        svc.req.goal = GOAL
        svc.req.max_velocity = 0.5
        svc.req.constraints = [{"data": "a"}, {"data": "b\u00e4"}]
        expected = plan(GOAL, 0.5, ["a", "b\u00e4"])
        expected["message"] = ""
        assert svc.call(LIMIT).to_dict() == expected
        # a dynamic array of structs arrives as a ctypes array of the md's structs, owned by
        # the request (so it is still intact after the call)
        constraints = provider.arguments["plan_path"]["constraints"]
        assert isinstance(constraints, ctypes.Array) and len(constraints) == 2
        assert [c.data for c in constraints] == ["a", "b\u00e4"]


def test_return_conventions(manager: Manager, provider: robot) -> None:
    with manager.client("caller") as clnt:
        scale = clnt.get_service("arm.scale", "lntest/scale")
        scale.req.values = [1.0, 2.0, 3.0]
        scale.req.factor = 3.0
        assert scale.call(LIMIT).values.tolist() == [3.0, 6.0, 9.0]  # bare numpy array
        scale.req.factor = -1.0
        assert scale.call(LIMIT).values.tolist() == [-1.0]  # bare list
        assert clnt.get_service("arm.ping", "lntest/ping").call(LIMIT).to_dict() == {}
        assert provider.arguments["ping"] == {}

        bad = clnt.get_service("arm.misbehave", "robot/set_gains")
        for mode, text in [
                ("none", "TypeError: arm.misbehave: returned None, but the response of "
                         "robot/set_gains has fields ok, message"),
                ("bare", "TypeError: arm.misbehave: returned int"),
                ("unknown", "KeyError"),
                ("raise", "ZeroDivisionError: division by zero")]:
            bad.req.profile_name = mode
            with pytest.raises(ln.LnServiceError) as info:
                bad.call(LIMIT)
            assert text in str(info.value), mode
        bad.req.profile_name = "none"  # still serving
        with pytest.raises(ln.LnServiceError, match="TypeError"):
            bad.call(LIMIT)
