"""Services and hostile RECLAIM_PORT frames across a manager restart: a provider registered
before it is found and called by a caller created after it, its socket kept for it; bad
re-registration data is refused port by port, a malformed frame closes only its connection,
and the manager keeps serving."""

from __future__ import annotations

import lnwire
from polling import wait_for
from services.conftest import GOAL, plan

import links_and_nodes as ln
from links_and_nodes.manager.frontends.launch import segments

from .conftest import LIMIT, Restarts, read_until


def test_provider_before_restart_is_called_after(restarts: Restarts) -> None:
    restarts.tool("service_tool", "provide", "rc.plan")
    before = restarts.services()["rc.plan"]
    restarts.restart()
    wait_for(lambda: "rc.plan" in restarts.services(), "the provider registered again")
    after = restarts.services()["rc.plan"]
    assert (after["unix_path"], after["tcp_port"]) == (before["unix_path"], before["tcp_port"])
    svc = restarts.client("caller").get_service("rc.plan", "robot/plan_path")
    svc.req.goal = GOAL
    svc.req.max_velocity = 0.5
    svc.req.constraints = [{"data": "after restart"}]
    assert svc.call(timeout=LIMIT).to_dict() == plan(GOAL, 0.5, ["after restart"])
    assert svc.call(timeout=LIMIT).status == 1  # and again on the same connection


def _reclaim(wire: lnwire.WireClient, request_id: int, kind: int, topic: str, layout: int,
             segment: str, reader: int = lnwire.NO_READER) -> lnwire.Reply:
    wire.send(lnwire.RECLAIM_PORT, lnwire.reclaim_body(
        request_id, kind, topic, "robot/joint_state", layout, 180, segment, reader))
    return wire.recv()


def test_hostile_reclaims_are_refused(restarts: Restarts) -> None:
    owner = restarts.client("owner")
    owner.publish("rc.a", "robot/joint_state")
    sub = owner.subscribe("rc.a", "robot/joint_state")
    owner.publish("rc.b", "robot/joint_state")
    with lnwire.WireClient(int(restarts.port)) as probe:  # the md's layout hash
        assert probe.hello("probe").type == lnwire.WELCOME
        layout = int(probe.topic_info("rc.a").layout_hash)
    ring_a, ring_b = (f"/ln.{restarts.instance}.{i}.1" for i in (1, 2))
    restarts.restart("--adopt-window", "30")
    wait_for(lambda: restarts.topics().get("rc.a", {}).get("subscribers") == 1,
             "the owner's ports taken back")
    with lnwire.WireClient(int(restarts.port)) as wire:
        assert wire.hello("hostile", flags=lnwire.HELLO_RECONNECT).type == lnwire.WELCOME
        cases = [  # (kind, topic, layout, segment, reader) -> code
            ((0, "rc.a", layout ^ 1, ring_a, lnwire.NO_READER), ln.LnLayoutError.code),
            ((1, "rc.a", layout, ring_a, 64), ln.LnInvalError.code),
            ((1, "rc.a", layout, ring_a, 0), ln.LnBusyError.code),  # the owner's slot
            ((0, "rc.a", layout, ring_a, 3), ln.LnInvalError.code),  # a publisher's slot
            ((0, "rc.a", layout, f"/ln.{restarts.instance}.99.1", lnwire.NO_READER),
             ln.LnNotfoundError.code),
            ((0, "rc.a", layout, ring_b, lnwire.NO_READER), ln.LnNotfoundError.code),
            ((0, "rc.a", layout, "/etc/passwd", lnwire.NO_READER), ln.LnInvalError.code),
            ((0, "rc.zz", layout, ring_a, lnwire.NO_READER), ln.LnNotfoundError.code),
            ((7, "rc.a", layout, ring_a, lnwire.NO_READER), ln.LnInvalError.code),
        ]
        for request_id, (args, code) in enumerate(cases, start=1):
            reply = _reclaim(wire, request_id, *args)
            assert (reply.type, reply.code) == (lnwire.ERROR, code), (args, reply)
        good = _reclaim(wire, 50, 0, "rc.a", layout, ring_a)  # a fine one still works
        assert good.type == lnwire.PORT_OK and good.segment.startswith(ring_a[:-1])
        # a body cut short is malformed: this connection only is closed
        body = lnwire.reclaim_body(51, 0, "rc.a", "robot/joint_state", layout, 180, ring_a)
        wire.send(lnwire.RECLAIM_PORT, body[:-2])
        assert wire.closed_by_peer()
    restarts.wait_log("closing: RECLAIM_PORT body too short")
    assert "refused: ELAYOUT" in restarts.log()
    # the manager serves on: a new publisher reaches the owner's subscriber
    late = restarts.client("late").publish("rc.a", "robot/joint_state")
    late.packet.cycle = 4242
    late.write()
    read_until(sub, lambda p: p.cycle == 4242, "the late publisher's sample")
    assert len(segments(restarts.instance)) == 2

