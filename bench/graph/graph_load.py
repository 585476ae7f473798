"""The system the graph benchmark draws, in one process:

    graph_load.py ADDRESS CLIENTS TOPICS_PER_CLIENT

CLIENTS clients (bench_p000, ...) each publish TOPICS_PER_CLIENT topics (bench.t0000, ...)
of md lntest/graph_sample and subscribe to as many of another client's, so the graph has
CLIENTS x TOPICS_PER_CLIENT topics, a publisher and a subscriber edge each.  Every topic gets
a sample a second (so the graph has rates); prints "ready" once everything is registered.
Runs until killed."""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

import links_and_nodes as ln

MD = "# A sample of the graph benchmark.\nuint64_t count\ndouble value\n"


def main() -> None:
    address, clients, per = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
    md_dir = Path(tempfile.mkdtemp(prefix="ln_graph_md_"))
    (md_dir / "lntest").mkdir()
    (md_dir / "lntest" / "graph_sample").write_text(MD)
    ln.add_message_definition_dir(str(md_dir))
    topics = clients * per
    handles = []
    pubs = []
    for c in range(clients):
        clnt = ln.client(f"bench_p{c:03d}", address)
        handles.append(clnt)
        for k in range(per):
            pubs.append(clnt.publish(f"bench.t{c * per + k:04d}", "lntest/graph_sample"))
    for c, clnt in enumerate(handles):  # each reads the topics of the client 7 further on
        other = (c + 7) % clients
        for k in range(per):
            clnt.subscribe(f"bench.t{(other * per + k) % topics:04d}",
                                 "lntest/graph_sample")
    print("ready", flush=True)
    n = 0
    while True:
        n += 1
        start = time.monotonic()
        for pub in pubs:
            pub.packet.count = n
            pub.write()
        time.sleep(max(0.0, 1.0 - (time.monotonic() - start)))


if __name__ == "__main__":
    main()
