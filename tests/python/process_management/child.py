"""A process for the process management tests; the last argument is always the test's
instance name, so the tests find every process they started in the process table.
    child.py ready TEXT MARKER            print "starting", then TEXT, then sleep until killed
    child.py exit CODE MARKER             exit with CODE at once
    child.py gate FILE MARKER             print "waiting", then "ready" once FILE exists
    child.py tree MARKER                  start a child and a setsid'd grandchild, print "ready"
    child.py publish TOPIC COUNT MARKER   publish COUNT samples at 200 Hz, print "ready" at the
                                          first, then stay alive without publishing
    child.py ignore-term MARKER           ignore SIGTERM, print "ready", sleep
    child.py crash-once FILE MARKER       the first time (FILE missing): create FILE, exit 1;
                                          then print "ready" and sleep"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time


def sleep_forever() -> None:
    while True:
        time.sleep(3600)


def main() -> None:
    mode, args = sys.argv[1], sys.argv[2:]
    if mode == "ready":
        print("starting", flush=True)
        print(args[0], flush=True)
        sleep_forever()
    elif mode == "exit":
        sys.exit(int(args[0]))
    elif mode == "gate":
        print("waiting", flush=True)
        while not os.path.exists(args[0]):
            time.sleep(0.01)
        print("ready", flush=True)
        sleep_forever()
    elif mode == "tree":
        marker = args[-1]
        subprocess.Popen([sys.executable, __file__, "ready", "child-up", marker])
        subprocess.Popen([sys.executable, __file__, "ready", "grandchild-up", marker],
                         start_new_session=True)
        print("ready", flush=True)
        sleep_forever()
    elif mode == "publish":
        import links_and_nodes as ln

        clnt = ln.client("publisher")
        pub = clnt.publish(args[0], "robot/joint_state")
        for i in range(int(args[1])):
            pub.packet.cycle = i
            pub.write()
            if i == 0:
                print("ready", flush=True)
            time.sleep(0.005)
        print("stalled", flush=True)
        sleep_forever()
    elif mode == "ignore-term":
        signal.signal(signal.SIGTERM, signal.SIG_IGN)
        print("ready", flush=True)
        sleep_forever()
    elif mode == "crash-once":
        if not os.path.exists(args[0]):
            open(args[0], "w").close()
            sys.exit(1)
        print("ready", flush=True)
        sleep_forever()


if __name__ == "__main__":
    main()
