"""The publisher of the introspection tests, a process of its own:

    probe_publisher.py ADDRESS TOPIC PERIOD MD_DIR [--wait-for-subscribers]

publishes lntest/probe (from MD_DIR) on TOPIC every PERIOD seconds, sample k (k = 1, 2, ...)
holding the values `probe_values(k)` says, and prints "ready" after the first.  Runs until
killed.  With MD_DIR tests/fixtures/md/introspect_other it publishes that directory's lntest/probe,
another layout under the same name."""

from __future__ import annotations

import sys
import time
from typing import Any

import links_and_nodes as ln


def probe_values(k: int) -> dict[str, Any]:
    """What sample k of lntest/probe holds (every value exact in binary)."""
    return {"count": k, "q": [k + j / 8 for j in range(7)],
            "target": {"position": [k, 2 * k, 3 * k], "orientation": [0.0, 0.0, 0.0, 1.0]},
            "gains": [0.1, 0.2, 0.3], "label": "probe",
            "trace": [k * 1000 + i for i in range(100)]}


def main() -> None:
    address, topic, period, md_dir = sys.argv[1:5]
    ln.add_message_definition_dir(md_dir)
    clnt = ln.client("probe_pub", address)
    pub = clnt.publish(topic, "lntest/probe",
                       wait_for_subscribers="--wait-for-subscribers" in sys.argv)
    other = "introspect_other" in md_dir
    k = 0
    while True:
        k += 1
        if other:
            pub.packet.count = k
        else:
            pub.packet.update(probe_values(k))
        pub.write()
        if k == 1:
            print("ready", flush=True)
        time.sleep(float(period))


if __name__ == "__main__":
    main()
