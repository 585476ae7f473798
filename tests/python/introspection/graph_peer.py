"""A subscriber and caller for the graph tests, a process of its own:

    graph_peer.py ADDRESS NAME TOPIC SERVICE MD_DIR

connects as client NAME, subscribes TOPIC (lntest/probe, queued) and calls SERVICE
(lntest/adjust) once, then prints "ready".  Runs until killed."""

from __future__ import annotations

import sys
import time

import links_and_nodes as ln


def main() -> None:
    address, name, topic, service, md_dir = sys.argv[1:6]
    ln.add_message_definition_dir(md_dir)
    clnt = ln.client(name, address)
    clnt.subscribe(topic, "lntest/probe", buffers=4)
    svc = clnt.get_service(service, "lntest/adjust")
    svc.req.values = [1.0, 2.0, 3.0]
    svc.req.name = b"peer"
    svc.call(timeout=10.0)
    print("ready", flush=True)
    while True:
        time.sleep(1.0)


if __name__ == "__main__":
    main()
