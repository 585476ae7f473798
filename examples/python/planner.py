"""A planner for the simulated arm: sets the controller's gains through the service
arm.set_gains (and shows a refused setting), commands a slow sine motion on robot.command and
follows robot.state in queued mode, so it sees every controller cycle, and reports what it saw.

Run by scripts/demo next to examples/c/arm_controller; the manager comes from $LN_MANAGER.
"""

from __future__ import annotations

import math
import sys

import links_and_nodes as ln


def set_gains(clnt: ln.client) -> bool:
    """Stiffer gains through the controller's service; then an unsafe setting it refuses."""
    svc = clnt.get_service("arm.set_gains", "robot/set_gains")
    svc.req.kp = [30.0] * 7
    svc.req.kd = [1.0] * 7
    svc.req.profile_name = "demo"
    resp = svc.call(timeout=5.0)
    print(f"planner: arm.set_gains kp=30 -> ok={resp.ok}", flush=True)
    svc.req.kp[3] = 500.0
    refused = svc.call(timeout=5.0)
    print(f"planner: arm.set_gains kp[3]=500 -> ok={refused.ok} ({refused.message})",
          flush=True)
    svc.close()
    return bool(resp.ok) and not refused.ok


def main() -> int:
    expected = int(sys.argv[1]) if len(sys.argv) > 1 else 2000
    clnt = ln.client("planner", sys.argv)
    command = clnt.publish("robot.command", "robot/command")
    # Queued: every cycle, with up to about a second of slack at 1 kHz.
    state = clnt.subscribe("robot.state", "robot/joint_state", buffers=min(1024, expected))
    print("planner: waiting for the arm controller", flush=True)
    received, last_cycle, gaps = 0, 0, 0
    gains_ok = None
    while received < expected:
        pkt = state.read(timeout=30.0)
        if pkt is None:
            print("planner: no joint state for 30 s, giving up", file=sys.stderr)
            return 1
        received += 1
        if gains_ok is None:  # the controller runs: its service is registered
            gains_ok = set_gains(clnt)
        gaps += pkt.cycle - last_cycle - 1 if last_cycle else 0
        last_cycle = pkt.cycle
        t = pkt.timestamp
        command.packet.timestamp = t
        command.packet.mode = 1
        command.packet.target[:] = [0.5 * math.sin(2 * math.pi * 0.5 * t + j) for j in range(7)]
        command.write()
        if pkt.cycle % 500 == 0:
            q = " ".join(f"{x:+.3f}" for x in pkt.position)
            print(f"planner: cycle {pkt.cycle:5d} t={t:6.3f}s q=[{q}]", flush=True)
    overruns = state.overruns
    print(f"planner: {received} states, {overruns} overruns, {gaps} missing cycles")
    clnt.close()
    return 0 if overruns == 0 and gaps == 0 and gains_ok else 1


if __name__ == "__main__":
    sys.exit(main())
