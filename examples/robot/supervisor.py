"""The supervisor of the demo robot system (robot.lnc): sets the controller's gains through
the service arm.set_gains, follows arm.state and the controller's arm.reference and prints,
once a second, statistics of the tracking error (target minus measured joint position, the two
matched by cycle).  After --switch-after seconds it asks for gains above the controller's
limits, which it refuses, and then for stiffer gains, which shrink the error.  SIGTERM or
SIGINT ends it with exit status 0.  The manager comes from $LN_MANAGER or -ln_manager.

    supervisor.py [--switch-after SECONDS] [--duration SECONDS]
"""

from __future__ import annotations

import argparse
import signal
import sys
import time
from types import FrameType

import numpy as np

import links_and_nodes as ln

# Gain profiles (kp in Nm/rad, kd in Nm s/rad per joint), for the simulated arm's inertias.
PROFILES: dict[str, tuple[list[float], list[float]]] = {
    "soft": ([50, 50, 30, 25, 12, 8, 4], [10, 10, 6, 5, 2.5, 1.6, 0.8]),
    "stiff": ([250, 250, 160, 120, 60, 40, 20], [22, 22, 14, 11, 5.5, 3.6, 1.8]),
    "unsafe": ([5000, 250, 160, 120, 60, 40, 20], [22, 22, 14, 11, 5.5, 3.6, 1.8]),
}
BUFFERS = 512  # queued: half a second of slack at 1 kHz

stop_signal: int | None = None


def on_signal(signum: int, frame: FrameType | None) -> None:
    global stop_signal
    stop_signal = signum


def set_gains(svc: ln.service, profile: str) -> bool:
    """Ask the controller for a gain profile; print and return whether it took it."""
    kp, kd = PROFILES[profile]
    svc.req.kp = kp
    svc.req.kd = kd
    svc.req.profile_name = profile
    resp = svc.call(timeout=5.0)
    if resp.ok:
        print(f"arm.set_gains '{profile}': accepted", flush=True)
    else:
        print(f"arm.set_gains '{profile}': refused ({resp.message})", flush=True)
    return bool(resp.ok)


class ErrorStats:
    """Tracking error over one reporting period."""

    def __init__(self) -> None:
        self.sum_sq = 0.0
        self.max = 0.0
        self.max_joint = 0
        self.samples = 0
        self.unmatched = 0  # references whose state we did not see (overrun)

    def add(self, error: np.ndarray) -> None:
        self.sum_sq += float(np.dot(error, error)) / error.size
        joint = int(np.argmax(np.abs(error)))
        if abs(error[joint]) > self.max:
            self.max, self.max_joint = float(abs(error[joint])), joint
        self.samples += 1

    def line(self, t: float, profile: str) -> str:
        rms = (self.sum_sq / self.samples) ** 0.5 if self.samples else float("nan")
        return (f"t={t:.0f} s tracking error rms {rms * 1e3:6.2f} mrad, "
                f"max {self.max * 1e3:6.2f} mrad (joint {self.max_joint}), "
                f"{self.samples} cycles, gains '{profile}'"
                + (f", {self.unmatched} unmatched" if self.unmatched else ""))


def first_gains(gains: ln.service, profile: str) -> bool:
    """Set the first gains. Under robot.lnc the controller is ready before we start; by hand
    it may not be yet, so this retries for 10 s (False, said on stderr, if it never
    answered)."""
    deadline = time.monotonic() + 10.0
    while True:
        try:
            set_gains(gains, profile)
            return True
        except ln.LnError as exc:
            if time.monotonic() > deadline or stop_signal is not None:
                print(f"supervisor: cannot call arm.set_gains: {exc}", file=sys.stderr)
                return False
            time.sleep(0.2)


def take_states(state: ln.subscriber, positions: dict[int, np.ndarray], newest: int,
                cycle: int) -> int:
    """Read the queued states up to `cycle` into `positions` (cycle -> measured position);
    the newest cycle read."""
    while newest < cycle:
        pkt = state.read(timeout=0.05)
        if pkt is None:
            break
        newest = int(pkt.cycle)
        positions[newest] = np.array(pkt.position)
    return newest


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--switch-after", type=float, default=3.0, metavar="SECONDS",
                        help="when to try the unsafe and then the stiff gains (default 3)")
    parser.add_argument("--duration", type=float, default=None, metavar="SECONDS",
                        help="exit by itself after this long (default: run until SIGTERM)")
    args, rest = parser.parse_known_args()
    signal.signal(signal.SIGTERM, on_signal)
    signal.signal(signal.SIGINT, on_signal)

    clnt = ln.client("supervisor", [sys.argv[0], *rest])
    state = clnt.subscribe("arm.state", "robot/joint_state", buffers=BUFFERS)
    reference = clnt.subscribe("arm.reference", "robot/joint_state", buffers=BUFFERS)
    gains = clnt.get_service("arm.set_gains", "robot/set_gains")
    profile = "soft"
    if not first_gains(gains, profile):
        clnt.close()
        return 1
    switched = False

    positions: dict[int, np.ndarray] = {}  # cycle -> measured position, not yet matched
    newest_state = 0
    stats = ErrorStats()
    report_at: float | None = None
    first = True
    started = time.monotonic()
    silent_since = time.monotonic()
    while stop_signal is None:
        if args.duration is not None and time.monotonic() - started >= args.duration:
            break
        ref = reference.read(timeout=0.2)
        if ref is None:
            if time.monotonic() - silent_since >= 2.0:
                print("no reference from the controller for 2 s", flush=True)
                silent_since = time.monotonic()
            continue
        silent_since = time.monotonic()
        cycle, t = int(ref.cycle), float(ref.timestamp)
        target = np.array(ref.position)
        # The controller publishes the reference of a cycle after reading its state, so the
        # state is already in our queue.
        newest_state = take_states(state, positions, newest_state, cycle)
        measured = positions.pop(cycle, None)
        for old in [c for c in positions if c < cycle]:
            del positions[old]
        if measured is None:
            stats.unmatched += 1
        else:
            stats.add(target - measured)
        if report_at is None:  # the first, partial second is not reported
            report_at = float(np.floor(t)) + 1.0
            first = True
        if t >= report_at:
            if not first:
                print(stats.line(t, profile), flush=True)
            first = False
            stats = ErrorStats()
            report_at = float(np.floor(t)) + 1.0
            if not switched and time.monotonic() - started >= args.switch_after:
                switched = True
                set_gains(gains, "unsafe")
                if set_gains(gains, "stiff"):
                    profile = "stiff"
    why = {None: "done", signal.SIGTERM: "stopped by SIGTERM",
           signal.SIGINT: "stopped by SIGINT"}[stop_signal]
    print(f"{why}; {state.overruns} state and {reference.overruns} reference "
          "samples overrun", flush=True)
    clnt.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
