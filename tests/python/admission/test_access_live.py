"""A live manager applying its `access` rules (docs/security.md, "Access rules"): it refuses
exactly what they deny with LN_EPERM, the rule's place in the text and a log line."""

from __future__ import annotations

import pytest
from lnwire import ERROR, FIND_SERVICE, REGISTER_SERVICE, find_service_body, register_service_body

from admission.clients import Client
from admission.conftest import Admission
from admission.test_access_rules import RULES
from admission.test_admission_key import LnPermError


def test_manager_refuses_what_the_rules_deny(admission: Admission) -> None:
    manager = admission.start(access=RULES)
    address = f"127.0.0.1:{manager.port}"
    with Client(address, "controller-1") as controller:
        controller.publish("arm.command")
        with pytest.raises(LnPermError) as info:
            controller.publish("arm.state")
        assert "client 'controller-1' may not publish 'arm.state': denied by the access rule " \
               "at " in str(info.value)
        lines = (admission.tmp / f"{admission.instance}.lnc").read_text().splitlines()
        assert f".lnc:{lines.index('deny publish arm.*: *') + 1}:1" in str(info.value)
        controller.subscribe("arm.state")
    manager.wait_log(r"client controller-1 \(\S+\): PUBLISH refused: EPERM: client "
                     r"'controller-1' may not publish 'arm.state'")
    wire = manager.client("guest-7")
    wire.send(FIND_SERVICE, find_service_body(1, "robot.stop", "m", 0))
    refused = wire.recv()
    assert refused.type == ERROR and refused.code == -17, refused
    assert "may not call 'robot.stop'" in refused.text
    wire.send(REGISTER_SERVICE, register_service_body(2, "robot.stop", "m", 0, "a|b"))
    refused = wire.recv()
    assert refused.type == ERROR and refused.code == -17, refused
    wire.send(FIND_SERVICE, find_service_body(3, "sensors.reset", "m", 0))
    assert wire.recv().code != -17  # allowed: the lookup itself answers (not found)
    wire.close()
