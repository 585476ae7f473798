"""A logger on the publisher's host keeps every sample although the network to the
subscriber's host loses 30 % of the datagrams (ln_relay with seeded loss in front of host
b's daemon): the capture happens before the network (docs/logging.md)."""

from __future__ import annotations

import numpy as np
from polling import wait_for

import links_and_nodes as ln

from .conftest import HERE, System
from .test_multihost import RELAY_PORT, TIMEOUT, _consecutive, _start_relay


def test_publisher_host_logger_loses_nothing_of_a_lossy_link(system: System) -> None:
    system.start_daemon("a")
    system.start_daemon("b", "--advertise-data-port", str(RELAY_PORT))
    system.start_daemon("c")
    _start_relay(system, "b", 0.3)
    lnc = system.lnc(
        system.process("pub", "a", "pub net.ctl nettest/sample --rate 200", "publishing")
        + system.process("sub", "b", "sub net.ctl nettest/sample --transport udp",
                         "subscribed"))
    system.run(lnc)
    lg = system.mgr.get_logger("flight")
    lg.add_topic("net.ctl", 100000)
    lg.enable()
    got = wait_for(lambda: len(r := system.received(system.output("sub"))) >= 200 and r,
                   "200 samples over UDP through 30 % loss", timeout=TIMEOUT * 2)
    assert not _consecutive([c for _, c, _ in got]), "nothing lost: the relay is not in the path"
    wait_for(lambda: lg.status()["topics"] and lg.status()["topics"][0]["received"] >= 300,
             "300 samples logged on host a")
    lg.disable()
    st = lg.status()["topics"][0]
    assert st["host"] == "a" and st["missed"] == 0 and st["dropped"] == 0
    ln.add_message_definition_dir(HERE / "md")
    data = lg.download()["net.ctl"]
    assert len(data) == st["stored"] == st["received"] >= 300
    assert np.all(np.diff(data["seq"].astype(np.int64)) == 1)
    assert np.array_equal(data["counter"], data["seq"])  # the publisher's n-th is seq n
