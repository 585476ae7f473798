"""A pull topic across hosts (network namespaces, as the network tests): the publisher runs
on host a, so the manager places the topic on a's ln_daemon only, through the link to that
remote daemon; a consumer on host c pulls it from a's address, and the network view shows
the producer's counters under host a."""

from __future__ import annotations

from netlab import in_netns
from network.conftest import HERE, System
from polling import wait_for

import links_and_nodes as ln

PORT = 6363  # every host has its own network stack: the default port is free on each


def test_pulled_from_the_publishers_host(system: System) -> None:
    system.start_daemons()
    lnc = system.lnc(system.process("pub", "a", "pub net.pull nettest/sample --rate 100",
                                    "publishing"),
                     extra=f"topics\nnet.pull: pull:ndn-udp, pull_port:{PORT}\n")
    mgr = system.run(lnc)

    def served() -> list:
        return [h for h in mgr.network()["pull"]
                if h["topics"] and not h["topics"][0]["error"]]

    (host,) = wait_for(served, "the pull topic served on host a")  # type: ignore[misc]
    assert host["host"] == "a" and host["topics"][0]["port"] == PORT
    ln.add_message_definition_dir(HERE / "md")
    uri = f"/ln/{system.instance}/net.pull"
    sub = in_netns(system.lab["c"].netns, lambda: ln.pull_subscribe(
        system.lab["a"].address, PORT, uri, "nettest/sample"))
    with sub:
        got = []
        while len(got) < 20:
            sample = sub.receive(30.0)
            assert sample is not None, sub.stats
            got.append(sample)
    assert [s.seq for s in got] == sorted({s.seq for s in got})
    for s in got:  # netclient publishes counter = seq, value = counter / 2
        assert s.message.counter == s.seq and s.message.value == s.seq * 0.5
    (host,) = mgr.network()["pull"]
    assert host["host"] == "a" and host["topics"][0]["data"] >= 20
    assert host["ports"][0]["packets"] >= 20
    assert [t["host"] for t in mgr.command("pull")["topics"]] == ["a"]
