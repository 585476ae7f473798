"""A planner for the simulated arm: commands a slow sine motion on robot.command and follows
robot.state in queued mode, so it sees every controller cycle, and reports what it saw.

Run by scripts/demo next to examples/c/arm_controller; the manager comes from $LN_MANAGER.
"""

from __future__ import annotations

import math
import sys

import links_and_nodes as ln


def main() -> int:
    expected = int(sys.argv[1]) if len(sys.argv) > 1 else 2000
    clnt = ln.client("planner", sys.argv)
    command = clnt.publish("robot.command", "robot/command")
    # Queued: every cycle, with up to about a second of slack at 1 kHz.
    state = clnt.subscribe("robot.state", "robot/joint_state", buffers=min(1024, expected))
    print("planner: waiting for the arm controller", flush=True)
    received, last_cycle, gaps = 0, 0, 0
    while received < expected:
        pkt = state.read(timeout=30.0)
        if pkt is None:
            print("planner: no joint state for 30 s, giving up", file=sys.stderr)
            return 1
        received += 1
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
    return 0 if overruns == 0 and gaps == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
