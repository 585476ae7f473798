"""Smoke test of an installed links_and_nodes (tests/installed/run): subscribes smoke.state
in queued mode, prints "subscribed", then checks that 100 samples of publisher.c arrive in
order with the values it wrote.  Exit status 0 when they did."""

import sys

import links_and_nodes as ln

SAMPLES = 100

clnt = ln.client("smoke_subscriber")
sub = clnt.subscribe("smoke.state", "robot/joint_state", buffers=64)
print("subscribed", flush=True)
seen, last = 0, 0
while seen < SAMPLES and (pkt := sub.read(timeout=10.0)) is not None:
    cycle = int(pkt.cycle)
    expected = [cycle * (j + 1) / 1000.0 for j in range(7)]
    if list(pkt.position) != expected:
        sys.exit(f"cycle {cycle}: position {list(pkt.position)}, expected {expected}")
    if seen and cycle != last + 1:
        sys.exit(f"cycle {cycle} after {last}: a sample was lost in queued mode")
    last, seen = cycle, seen + 1
if seen < SAMPLES:
    sys.exit(f"only {seen} samples arrived")
print(f"subscriber: {seen} samples in order, cycles {last - seen + 1}..{last}", flush=True)
