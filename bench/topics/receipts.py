"""What a throughput receiver of the topic benchmark reports, shared by the ln, iceoryx2
and pyzmq receivers: samples received in order or not, the time from the first to the last,
and the minor page faults from sample WARM on (when it counts them)."""

from __future__ import annotations

import json
import resource
import time


def minflt() -> int:
    return resource.getrusage(resource.RUSAGE_SELF).ru_minflt


class Receipts:
    """Feed it every sample's counter with got(); report() prints the JSON line."""

    def __init__(self, warm: int | None = None) -> None:
        self.warm = warm  # None: page faults are not counted
        self.received = self.disorder = self.last = self.counted = self.faults = 0
        self.first_ns = self.last_ns = 0

    def got(self, counter: int) -> None:
        self.last_ns = time.perf_counter_ns()
        if self.warm is not None and (self.counted or counter >= self.warm):
            if not self.counted:
                self.faults = minflt()
            self.counted += 1
        if self.received == 0:
            self.first_ns = self.last_ns
        elif counter <= self.last:
            self.disorder += 1
        self.received += 1
        self.last = counter

    def done(self, count: int) -> bool:
        """Whether the sample numbered count - 1 came."""
        return self.received > 0 and self.last + 1 >= count

    def report(self, overruns: int = 0) -> None:
        out = {"received": self.received, "overruns": overruns, "disorder": self.disorder,
               "elapsed_s": (self.last_ns - self.first_ns) * 1e-9}
        if self.warm is not None:
            out["minflt"] = minflt() - self.faults if self.counted else 0
            out["fault_samples"] = self.counted
        print(json.dumps(out))
