"""An asyncio tool for the demo robot (examples/robot/robot.lnc): one event loop follows
arm.state, arm.command and arm.reference (every sample, through `async for`) and sets the
controller's gains through the service arm.set_gains, with no thread per topic and no
polling: the loop waits on libln's waitset (docs/waiting.md, "Python and asyncio").

It waits for a publisher of each topic, asks for the gain profile, prints once a second how
many samples of each topic came and the newest cycle, and ends after --samples samples of
every topic, after --duration seconds, or on SIGINT/SIGTERM, with a summary line and exit
status 0 (1 if the controller never answered).  The manager comes from $LN_MANAGER or
-ln_manager.

    asyncio_tool.py [--profile soft|stiff] [--samples N] [--duration SECONDS]
"""

from __future__ import annotations

import argparse
import asyncio
import signal
import sys
import time

import links_and_nodes as ln

TOPICS = {"arm.state": "robot/joint_state", "arm.command": "robot/command",
          "arm.reference": "robot/joint_state"}
PROFILES: dict[str, tuple[list[float], list[float]]] = {
    "soft": ([50, 50, 30, 25, 12, 8, 4], [10, 10, 6, 5, 2.5, 1.6, 0.8]),
    "stiff": ([250, 250, 160, 120, 60, 40, 20], [22, 22, 14, 11, 5.5, 3.6, 1.8]),
}
BUFFERS = 512  # queued: half a second of slack at 1 kHz, so that every sample is seen


class Follower:
    """Counts the samples of one topic (and remembers what the newest said)."""

    def __init__(self, sub: ln.subscriber) -> None:
        self.sub = sub
        self.count = 0
        self.newest = ""

    async def run(self, enough: int | None, done: asyncio.Event) -> None:
        async for sample in self.sub:
            self.count += 1
            self.newest = (f"cycle {sample.cycle}" if hasattr(sample, "cycle")
                           else f"mode {sample.mode}")
            if enough is not None and self.count >= enough:
                break
        done.set()


async def set_gains(svc: ln.service, profile: str, limit: float) -> bool:
    """Ask for a gain profile, retrying while the controller is not there yet (`limit` s)."""
    kp, kd = PROFILES[profile]
    deadline = time.monotonic() + limit
    while True:
        try:
            resp = await svc.call_async({"kp": kp, "kd": kd, "profile_name": profile},
                                        timeout=5.0)
            break
        except ln.LnError as exc:
            if time.monotonic() > deadline:
                print(f"asyncio_tool: cannot call arm.set_gains: {exc}", file=sys.stderr)
                return False
            await asyncio.sleep(0.2)
    verdict = "accepted" if resp.ok else f"refused ({resp.message})"
    print(f"arm.set_gains '{profile}': {verdict}", flush=True)
    return True


async def report(followers: dict[str, Follower]) -> None:
    """A line a second: samples of each topic since the last line."""
    last = {name: 0 for name in followers}
    while True:
        await asyncio.sleep(1.0)
        parts = []
        for name, f in followers.items():
            parts.append(f"{name} {f.count - last[name]} ({f.newest})")
            last[name] = f.count
        print("last second: " + ", ".join(parts), flush=True)


async def main(args: argparse.Namespace, rest: list[str]) -> int:
    loop = asyncio.get_running_loop()
    stop = asyncio.Event()
    stopped_by: list[str] = []
    for signum in (signal.SIGINT, signal.SIGTERM):
        loop.add_signal_handler(signum, lambda s=signum: (stopped_by.append(
            signal.Signals(s).name), stop.set()))

    with ln.client("asyncio_tool", [sys.argv[0], *rest]) as clnt:
        followers = {name: Follower(clnt.subscribe(name, md, buffers=BUFFERS))
                     for name, md in TOPICS.items()}
        gains = clnt.get_service("arm.set_gains", "robot/set_gains")
        for name, f in followers.items():
            if not await clnt.wait_publisher(f.sub, timeout=args.wait):
                print(f"asyncio_tool: no publisher of {name} within {args.wait} s",
                      file=sys.stderr)
                return 1
        if not await set_gains(gains, args.profile, args.wait):
            return 1
        finished = [asyncio.Event() for _ in followers]
        tasks = [asyncio.create_task(f.run(args.samples, done))
                 for f, done in zip(followers.values(), finished, strict=True)]
        tasks.append(asyncio.create_task(report(followers)))
        ends = [asyncio.create_task(stop.wait())]
        ends += [asyncio.create_task(asyncio.wait_for(asyncio.gather(
            *(done.wait() for done in finished)), args.duration))]
        await asyncio.wait(ends, return_when=asyncio.FIRST_COMPLETED)
        for task in tasks + ends:
            task.cancel()  # each leaves nothing attached
        await asyncio.gather(*tasks, *ends, return_exceptions=True)
        why = f"stopped by {stopped_by[0]}" if stopped_by else "done"
        print(f"{why}: " + ", ".join(f"{name} {f.count} samples"
                                     for name, f in followers.items()), flush=True)
    return 0


def parse() -> tuple[argparse.Namespace, list[str]]:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--profile", choices=sorted(PROFILES), default="soft",
                        help="the gains to ask for (default soft)")
    parser.add_argument("--samples", type=int, default=None, metavar="N",
                        help="end once every topic gave N samples (default: never)")
    parser.add_argument("--duration", type=float, default=None, metavar="SECONDS",
                        help="end after this long (default: never)")
    parser.add_argument("--wait", type=float, default=10.0, metavar="SECONDS",
                        help="how long to wait for the publishers and the service")
    return parser.parse_known_args()


if __name__ == "__main__":
    arguments, others = parse()
    sys.exit(asyncio.run(main(arguments, others)))
