"""A process for the resource tests; the last argument is always the test's instance name,
so the tests find every process they started in the process table.
    resource_child.py busy MARKER          print "ready", then keep one core busy
    resource_child.py alloc MIB MARKER     allocate MIB MiB, write every page, print "ready",
                                           sleep"""

from __future__ import annotations

import sys
import time


def main() -> None:
    mode, args = sys.argv[1], sys.argv[2:]
    if mode == "busy":
        print("ready", flush=True)
        n = 0
        while True:
            n += 1
    elif mode == "alloc":
        block = bytearray(int(args[0]) << 20)
        for i in range(0, len(block), 4096):  # touch every page: resident, not just mapped
            block[i] = 1
        print("ready", flush=True)
        while True:
            time.sleep(3600)
            block[0] += 1
    else:
        sys.exit(f"unknown mode {mode}")


if __name__ == "__main__":
    main()
