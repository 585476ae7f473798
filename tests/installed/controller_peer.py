"""The Python side of examples/cmake's controller in tests/installed/run: subscribes
PREFIX.state, publishes a reference on PREFIX.reference, runs the controller (argv[1]) for
SAMPLES samples and checks that they all arrive in order with the values it wrote and that
it got the reference.  Manager from $LN_MANAGER.  Exit status 0 when all of that held."""

import subprocess
import sys

import links_and_nodes as ln

SAMPLES = 20
PREFIX = "installed_cmake"

clnt = ln.client("cmake_peer")
sub = clnt.subscribe(f"{PREFIX}.state", "robot/joint_state", buffers=SAMPLES + 8)
pub = clnt.publish(f"{PREFIX}.reference", "robot/joint_state")
pub.packet.cycle = 77
proc = subprocess.Popen([sys.argv[1], PREFIX, str(SAMPLES)], stdout=subprocess.PIPE, text=True)
seen = []
while proc.poll() is None or len(seen) < SAMPLES:
    pub.write()  # again every round: there whenever the controller reads
    pkt = sub.read(timeout=0.05)
    if pkt is None:
        if proc.poll() is not None:
            break
        continue
    cycle = int(pkt.cycle)
    expected = [cycle * (j + 1) / 1000.0 for j in range(7)]
    if list(pkt.position) != expected:
        proc.kill()
        sys.exit(f"cycle {cycle}: position {list(pkt.position)}, expected {expected}")
    seen.append(cycle)
out, _ = proc.communicate(timeout=60)
print(out, end="")
if proc.returncode != 0:
    sys.exit(f"the controller exited with status {proc.returncode}")
if seen != list(range(1, SAMPLES + 1)):
    sys.exit(f"samples {seen}, expected cycles 1..{SAMPLES} in order")
if "controller: reference cycle 77 " not in out:
    sys.exit("the controller did not report the reference")
print(f"cmake_peer: {SAMPLES} samples in order; the controller got the reference")
