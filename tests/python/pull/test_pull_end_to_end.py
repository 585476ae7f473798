"""Pull topics end to end (docs/pull.md): a `.lnc` with `pull:ndn-udp`, a C publisher, the
manager placing the topic on the publisher host's ln_daemon, and the Python consumer pulling
it: samples equal to what was published in increasing seq, sync giving the latest, the
network view and `ln_manager network|pull --json` showing the producer's counters, and the
topic gone from the daemon when its publisher leaves or the manager quits."""

from __future__ import annotations

import json
import signal

from polling import wait_for

import links_and_nodes as ln

from . import ndn_wire as w
from .conftest import PullLab, udp_port_free

TOPIC = "arm.state"


def take(sub: ln.pull.PullSubscription, n: int) -> list[ln.PullSample]:
    out = []
    while len(out) < n:
        sample = sub.receive(30.0)
        assert sample is not None, f"no sample after {len(out)}: {sub.stats}"
        out.append(sample)
    return out


def check_joint(sample: ln.PullSample) -> None:
    # topic_tool pub-loop writes cycle = seq and position[j] = cycle + j/8
    assert sample.message.cycle == sample.seq
    assert sample.message.position[3] == sample.seq + 3 / 8


def test_published_samples_pulled_through_the_manager(pulllab: PullLab) -> None:
    pulllab.serve()
    pub = pulllab.publisher(TOPIC, 2000)
    pulllab.served(TOPIC)
    (listed,) = pulllab.pull_topics()
    assert (listed["name"], listed["port"], listed["signature"]) == \
        (pulllab.uri(TOPIC), pulllab.port, "DigestSha256")
    with ln.pull_subscribe("127.0.0.1", pulllab.port, pulllab.uri(TOPIC),
                           "robot/joint_state") as sub:
        samples = take(sub, 50)
    seqs = [s.seq for s in samples]
    assert seqs == sorted(set(seqs))
    for s in samples:
        check_joint(s)
    # sync: a new consumer's first sample is at least the latest the producer had before
    _, topics = pulllab.counters()
    latest = topics[TOPIC]["latest_seq"]
    assert latest >= seqs[-1]
    with ln.pull_subscribe("127.0.0.1", pulllab.port, pulllab.uri(TOPIC),
                           "robot/joint_state") as sub:
        first = take(sub, 1)[0]
    assert first.seq >= latest
    check_joint(first)
    port, topics = pulllab.counters()
    t = topics[TOPIC]
    assert t["syncs"] >= 2 and t["data"] >= 51 and t["interests"] >= t["syncs"] + 50
    assert (t["name"], t["port"], t["error"]) == (pulllab.uri(TOPIC), pulllab.port, "")
    assert port["port"] == pulllab.port and port["packets"] >= t["interests"]
    assert port["bad"] == port["unknown"] == port["other"] == 0
    # the same through `ln_manager network --json` and the text views
    cli = pulllab.cli("network", "--json")
    assert cli.returncode == 0, cli.stderr
    (host,) = json.loads(cli.stdout)["pull"]
    assert host["topics"][0]["topic"] == TOPIC and host["topics"][0]["data"] >= t["data"]
    text = pulllab.cli("network").stdout
    assert "pull topic" in text and TOPIC in text and "interests" in text
    listing = pulllab.cli("pull", "--json")
    assert json.loads(listing.stdout)[0]["name"] == pulllab.uri(TOPIC)
    assert pulllab.uri(TOPIC) in pulllab.cli("pull").stdout
    # the publisher leaves: the topic leaves the daemon, which lets the port go
    pub.send_signal(signal.SIGKILL)
    wait_for(lambda: pulllab.pull_topics() == [], "pull topic removed after its publisher")
    wait_for(lambda: udp_port_free(pulllab.port), "the daemon letting the pull port go")
    assert pulllab.network()["pull"] == []


def test_manager_quit_removes_the_topic_from_the_daemon(pulllab: PullLab) -> None:
    pulllab.serve()
    pulllab.publisher(TOPIC, 2000)
    pulllab.served(TOPIC)
    assert not udp_port_free(pulllab.port)
    with pulllab.lab.connect() as mgr:
        mgr.command("quit")
    wait_for(lambda: udp_port_free(pulllab.port), "the pull port let go after quit")


def test_hmac_key_signs_data_with_type_4(pulllab: PullLab) -> None:
    key = bytes(range(1, 21))
    pulllab.serve(extra=f", pull_key:{key.hex()}")
    pulllab.publisher(TOPIC, 2000)
    pulllab.served(TOPIC)
    sync = w.interest(w.name_value(pulllab.uri(TOPIC), None, ("sync",)), nonce=77,
                      can_be_prefix=True, must_be_fresh=True)
    reply = pulllab.ask(sync)
    assert reply is not None
    d = w.decode_data(reply)
    assert d.signature_type == 4 and len(d.signature) == 32
    assert w.verify(d, key) and not w.verify(d, b"wrong key")
    (kind, value) = w.components(d.name)[-1]
    assert kind == w.SEQ and d.freshness_ms == 0
    content = w.decode_pull_content(d.content)
    assert int.from_bytes(content[w.PULL_LATEST], "big") == int.from_bytes(value, "big")
    seq = int.from_bytes(value, "big")
    sample = w.decode_data(pulllab.ask(w.interest(w.name_value(pulllab.uri(TOPIC), seq),
                                                  nonce=78)) or b"")
    assert sample.signature_type == 4 and w.verify(sample, key)
    assert sample.freshness_ms == 1000
    with ln.pull_subscribe("127.0.0.1", pulllab.port, pulllab.uri(TOPIC),
                           "robot/joint_state") as sub:
        for s in take(sub, 5):
            check_joint(s)
