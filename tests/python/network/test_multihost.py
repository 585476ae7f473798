"""Topics and services across hosts, on separate network stacks (docs/network.md): a
publisher on host a with subscribers on b and c, 8 MiB samples over UDP and over TCP, TCP and UDP
through 20 % injected loss (ln_relay between the daemons), remote service calls, a daemon
killed and restarted, a host cut off.  Every assertion is about what arrived, never about
how fast."""

from __future__ import annotations

import json
import sys

import pytest
from polling import wait_for

from .conftest import DAEMON_PORT, HERE, System

TIMEOUT = 60.0
RELAY_PORT = 54400


def _consecutive(counters: list[int]) -> bool:
    return all(b == a + 1 for a, b in zip(counters, counters[1:], strict=False))


def _start_relay(system: System, host: str, loss: float) -> None:
    """ln_relay in front of `host`'s daemon: its data port is advertised as RELAY_PORT,
    where the relay listens (UDP and TCP) and passes data on with seeded loss."""
    h = system.lab[host]
    ready = system.tmp / f"relay-{host}.json"
    target = f"127.0.0.1:{DAEMON_PORT + 1}"
    h.popen([sys.executable, "-m", "links_and_nodes.relay.cli",
             "--udp", f"{h.address}:{RELAY_PORT}", target,
             "--tcp", f"{h.address}:{RELAY_PORT}", target,
             "--loss", str(loss), "--seed", "7", "--ready-file", str(ready)],
            env=system.env(h), log=f"relay-{host}.log")
    wait_for(ready.exists, "the relay to listen")
    assert json.loads(ready.read_text())["seed"] == 7


def test_big_samples_reach_two_hosts_over_udp(system: System) -> None:
    system.start_daemons()
    lnc = system.lnc(
        system.process("pub", "a", "pub net.blob nettest/blob --rate 4", "publishing")
        + system.process("sub_b", "b", "sub net.blob nettest/blob", "subscribed")
        + system.process("sub_c", "c", "sub net.blob nettest/blob", "subscribed"))
    system.run(lnc)
    for sub in ("sub_b", "sub_c"):
        got = wait_for(lambda sub=sub: len(r := system.received(system.output(sub))) >= 4
                       and r, f"{sub} to receive 8 MiB samples", timeout=TIMEOUT)
        assert all(ok for _, _, ok in got), f"{sub}: corrupt 8 MiB sample"
        # the original sequence numbers: the publisher's n-th sample is seq n on every host
        assert all(seq == counter for seq, counter, _ in got), got
    stream = system.stream("net.blob", "a", "b")
    assert stream is not None and stream["transport"] == "udp" and stream["active"]
    wait_for(lambda: (s := system.stream("net.blob", "a", "c")) and s["received"] >= 4,
             "the manager's statistics to count a -> c")
    pairs = {(p["src"], p["dst"]) for p in system.mgr.network()["pairs"]}
    assert pairs == {("a", "b"), ("a", "c")}
    hosts = {h["name"]: h for h in system.mgr.hosts()}
    assert all(hosts[h]["state"] == "up" for h in "abc"), hosts


def test_big_samples_over_tcp_arrive_every_one_whole_and_in_order(system: System) -> None:
    """8 MiB samples over TCP at a rate the link carries: sent from the publisher's ring slot,
    received whole into the subscriber host's ring (docs/network.md, "Sender", "Receiver");
    every one arrives, intact, in order, and the stream counts no drop."""
    system.start_daemons()
    lnc = system.lnc(
        system.process("pub", "a", "pub net.blob nettest/blob --rate 10", "publishing")
        + system.process("sub", "b", "sub net.blob nettest/blob --buffers 8", "subscribed"),
        extra="topics\nnet.*: transport: tcp\n")
    system.run(lnc)
    got = wait_for(lambda: len(r := system.received(system.output("sub"))) >= 30 and r,
                   "30 samples of 8 MiB over TCP", timeout=TIMEOUT * 2)
    assert all(ok for _, _, ok in got), "corrupt 8 MiB sample"
    counters = [counter for _, counter, _ in got]
    assert _consecutive(counters), f"TCP lost samples: {counters}"
    assert all(seq == counter for seq, counter, _ in got)
    stream = wait_for(lambda: (s := system.stream("net.blob", "a", "b")) and s["received"] >= 30
                      and s, "the manager's statistics to count a -> b")
    assert stream["transport"] == "tcp" and stream["drops"] == 0, stream


def test_tcp_topic_delivers_every_sample_through_loss(system: System) -> None:
    system.start_daemon("a")
    system.start_daemon("b", "--advertise-data-port", str(RELAY_PORT))
    system.start_daemon("c")
    _start_relay(system, "b", 0.2)
    lnc = system.lnc(
        system.process("pub", "a", "pub net.log nettest/sample --rate 50", "publishing")
        + system.process("sub", "b", "sub net.log nettest/sample --buffers 64",
                         "subscribed"),
        extra="topics\nnet.*: transport: tcp\n")
    system.run(lnc)
    got = wait_for(lambda: len(r := system.received(system.output("sub"))) >= 150 and r,
                   "150 samples over TCP through 20 % loss", timeout=TIMEOUT * 2)
    counters = [counter for _, counter, _ in got]
    assert _consecutive(counters), f"TCP lost samples: {counters}"
    assert all(seq == counter for seq, counter, _ in got)
    stream = system.stream("net.log", "a", "b")
    assert stream is not None and stream["transport"] == "tcp"
    assert stream["drops"] == 0
    relay_log = system.log("relay-b.log")
    assert "tcp" in relay_log


def test_udp_topic_keeps_the_newest_samples_through_loss(system: System) -> None:
    system.start_daemon("a")
    system.start_daemon("b", "--advertise-data-port", str(RELAY_PORT))
    system.start_daemon("c")
    _start_relay(system, "b", 0.2)
    lnc = system.lnc(
        system.process("pub", "a", "pub net.ctl nettest/sample --rate 200", "publishing")
        + system.process("sub", "b", "sub net.ctl nettest/sample --transport udp",
                         "subscribed"))
    system.run(lnc)
    got = wait_for(lambda: len(r := system.received(system.output("sub"))) >= 200 and r,
                   "200 samples over UDP through 20 % loss", timeout=TIMEOUT * 2)
    counters = [counter for _, counter, _ in got]
    assert counters == sorted(set(counters)), "UDP delivered an older sample after a newer"
    assert not _consecutive(counters), "no sample was lost: the relay is not in the path"
    assert all(seq == counter for seq, counter, _ in got)
    first_max = counters[-1]
    # and it goes on: newer samples keep arriving despite the loss
    wait_for(lambda: system.received(system.output("sub"))[-1][1] > first_max + 100,
             "newer samples after the first 200")
    stream = system.stream("net.ctl", "a", "b")
    assert stream is not None and stream["transport"] == "udp"


def test_service_calls_across_hosts(system: System) -> None:
    system.start_daemons()
    lnc = system.lnc(
        system.process("provider", "a", "provide net.echo", "providing")
        + system.process("caller", "b", "call net.echo --count 12", "calls done",
                         depends_on="provider"))
    mgr = system.run(lnc)
    calls = [line for line in system.output("caller") if line.startswith("call ")]
    assert len(calls) == 12 and all(" OK " in line for line in calls), calls
    service = {s["name"]: s for s in mgr.services()}["net.echo"]
    # provided on a, called from b: the caller had to take the TCP address
    assert service["host_id"] == system.lab["a"].host_id
    assert service["tcp_host"] == system.lab["a"].address and service["tcp_port"] > 0


def test_daemon_restart_resumes_forwarding(system: System) -> None:
    system.start_daemons()
    lnc = system.lnc(
        system.process("pub", "a", "pub net.state nettest/sample --rate 100", "publishing")
        + system.process("sub_c", "c", "sub net.state nettest/sample", "subscribed"))
    mgr = system.run(lnc)
    sub_b = system.client("b", "sub", "net.state", "nettest/sample")
    wait_for(lambda: len(system.client_received(sub_b)) >= 20, "b to receive")
    before = {k: system.stream("net.state", "a", k) for k in "bc"}
    daemon_a = system.daemons["a"]
    pid_a = daemon_a.pid
    system.daemons["b"].kill()
    wait_for(lambda: {h["name"]: h for h in mgr.hosts()}["b"]["state"] == "unreachable",
             "the manager to see b's daemon gone")
    c_during = len(system.received(system.output("sub_c")))
    system.daemons["b"].restart()
    wait_for(lambda: {h["name"]: h for h in mgr.hosts()}["b"]["state"] == "up",
             "b's daemon back")
    seen = system.client_received(sub_b)[-1][1]
    wait_for(lambda: system.client_received(sub_b)[-1][1] > seen + 50,
             "forwarding to b to resume after its daemon's restart")
    # a and c were not touched: same daemon, same streams, c kept receiving
    assert daemon_a.pid == pid_a and daemon_a.running()
    after = {k: system.stream("net.state", "a", k) for k in "bc"}
    assert before["b"] is not None and after["b"] is not None
    assert after["b"]["token"] == before["b"]["token"]
    assert before["c"] is not None and after["c"] is not None
    assert after["c"]["token"] == before["c"]["token"]
    assert len(system.received(system.output("sub_c"))) > c_during
    got_b = system.client_received(sub_b)
    assert all(seq == counter for seq, counter, _ in got_b)


def test_receiving_daemon_killed_during_big_tcp_samples_resumes_whole(system: System) -> None:
    """The receiving daemon is SIGKILLed while 8 MiB frames stream into its host's ring (it
    may die in the middle of filling a slot: tests/c/test_ring_tap.c kills a writer there on
    purpose); after its restart the stream goes on and every sample the subscriber gets is
    whole, in publish order."""
    system.start_daemons()
    lnc = system.lnc(
        system.process("pub", "a", "pub net.blob nettest/blob --rate 30", "publishing"),
        extra="topics\nnet.*: transport: tcp\n")
    mgr = system.run(lnc)
    sub = system.client("b", "sub", "net.blob", "nettest/blob", "--buffers", "8")
    wait_for(lambda: len(system.client_received(sub)) >= 10, "b to receive 8 MiB samples",
             timeout=TIMEOUT)
    system.daemons["b"].kill()
    wait_for(lambda: {h["name"]: h for h in mgr.hosts()}["b"]["state"] == "unreachable",
             "the manager to see b's daemon gone")
    system.daemons["b"].restart()
    wait_for(lambda: {h["name"]: h for h in mgr.hosts()}["b"]["state"] == "up",
             "b's daemon back")
    seen = system.client_received(sub)[-1][1]
    wait_for(lambda: system.client_received(sub)[-1][1] > seen + 10,
             "big samples to b to resume after its daemon's restart", timeout=TIMEOUT)
    got = system.client_received(sub)
    assert all(ok for _, _, ok in got), "a torn or corrupt 8 MiB sample reached b"
    counters = [counter for _, counter, _ in got]
    assert counters == sorted(set(counters)), "an older sample after a newer one"
    assert all(seq == counter for seq, counter, _ in got)


def test_unreachable_host_is_reported_and_others_go_on(system: System) -> None:
    system.start_daemons()
    lnc = system.lnc(
        system.process("pub", "a", "pub net.state nettest/sample --rate 100", "publishing")
        + system.process("sub_b", "b", "sub net.state nettest/sample", "subscribed")
        + system.process("sub_c", "c", "sub net.state nettest/sample", "subscribed"))
    mgr = system.run(lnc)
    wait_for(lambda: len(system.received(system.output("sub_b"))) >= 20, "b to receive")
    system.lab["c"].disconnect()
    host_c = wait_for(lambda: (h := {h["name"]: h for h in mgr.hosts()}["c"])["state"]
                      == "unreachable" and h, "the manager to mark c unreachable")
    assert host_c["error"], "an unreachable host must say why"
    seen = system.received(system.output("sub_b"))[-1][1]
    wait_for(lambda: system.received(system.output("sub_b"))[-1][1] > seen + 100,
             "a -> b to go on while c is unreachable")
    hosts = {h["name"]: h for h in mgr.hosts()}
    assert hosts["a"]["state"] == "up" and hosts["b"]["state"] == "up"
    system.lab["c"].reconnect()
    wait_for(lambda: {h["name"]: h for h in mgr.hosts()}["c"]["state"] == "up",
             "c back", timeout=TIMEOUT)


def test_forwarding_through_a_gateway_host(system: System) -> None:
    """a and b share no network (as the .lnc declares them), c is in both: samples go
    a -> c -> b, c holding a ring of the topic only to pass them on."""
    system.start_daemons()
    networks = """network left
member_interfaces: a/eth0, c/eth0

network right
member_interfaces: c/eth0, b/eth0
"""
    lnc = system.lnc(
        system.process("pub", "a", "pub net.far nettest/sample --rate 100", "publishing")
        + system.process("sub", "b", "sub net.far nettest/sample", "subscribed"),
        extra=networks)
    mgr = system.run(lnc)
    got = wait_for(lambda: len(r := system.received(system.output("sub"))) >= 50 and r,
                   "b to receive through c")
    assert all(seq == counter for seq, counter, _ in got)
    hops = {(s["src"], s["dst"]) for s in mgr.network()["streams"] if s["topic"] == "net.far"}
    assert hops == {("a", "c"), ("c", "b")}, hops
    shm = system.lab["c"].path("/dev/shm")
    assert [f for f in shm.iterdir() if system.instance in f.name], "no ring on the gateway"
    mgr.stop("sub")
    wait_for(lambda: not [s for s in mgr.network()["streams"] if s["topic"] == "net.far"],
             "the streams to end with the last remote subscriber")
    wait_for(lambda: not [f for f in shm.iterdir() if system.instance in f.name],
             "the gateway's ring to go with its streams")


def test_a_publisher_back_on_its_host_reaches_the_other_hosts(system: System) -> None:
    """The publisher on a ends while b's subscriber keeps the topic, and a new one starts
    on a: its samples continue the topic's sequence numbers, so b takes them (a ring on a
    counting from 1 again would have b drop them all as stale)."""
    system.start_daemons()
    lnc = system.lnc(system.process("sub", "b", "sub net.again nettest/sample", "subscribed"))
    mgr = system.run(lnc)

    def publishers() -> int:
        return sum(t["publishers"] for t in mgr.topics() if t["name"] == "net.again")

    first = system.client("a", "pub", "net.again", "nettest/sample", "--count", "200",
                          "--rate", "400")
    assert first.log_path is not None
    wait_for(lambda: "published 200" in first.log_path.read_text(), "200 samples published")
    wait_for(lambda: system.received(system.output("sub")), "b to receive")
    first.kill()
    first.wait()
    wait_for(lambda: publishers() == 0, "the manager to see the publisher gone")
    system.client("a", "pub", "net.again", "nettest/sample", "--count", "20", "--rate", "50")
    got = wait_for(lambda: [r for r in system.received(system.output("sub")) if r[0] > 200],
                   "b to receive the second publisher's samples")
    assert all(1 <= counter <= 20 and seq == 200 + counter for seq, counter, _ in got), got


@pytest.mark.parametrize("transport", ["udp", "tcp"])
def test_a_waitset_on_another_host_sees_samples_and_the_publisher_gone_and_back(
        system: System, transport: str) -> None:
    """A waitset on b watches a topic published on a: the forwarded samples wake it (the
    receiving daemon rings its bell), and the publisher's death and a new publisher reach it
    as "gone" and "back" through the counts the manager sets on b's ring."""
    system.start_daemons()
    lnc = system.lnc(system.process("watch", "b", f"watch net.ws nettest/sample "
                                    f"--transport {transport}", "watching"))
    system.run(lnc)

    def events() -> list[str]:
        return [line for line in system.output("watch") if line in ("back", "gone")
                or line.startswith("got ")]

    def counters(lines: list[str]) -> list[int]:
        return [int(line.split()[2]) for line in lines if line.startswith("got ")]

    first = system.client("a", "pub", "net.ws", "nettest/sample", "--rate", "50")
    got = wait_for(lambda: len(counters(events())) >= 3 and events(), "b to see samples")
    assert got[0] == "back", got
    seen = counters(got)
    assert seen == sorted(seen) and len(set(seen)) == len(seen), got
    first.kill()
    first.wait()
    wait_for(lambda: "gone" in events(), "the waitset on b to see the publisher gone")
    system.client("a", "pub", "net.ws", "nettest/sample", "--rate", "50")

    def after_gone() -> list[str] | None:
        lines = events()
        tail = lines[lines.index("gone"):]
        return tail if len(counters(tail)) >= 3 else None

    after = wait_for(after_gone, "the new publisher's samples")
    assert after[:2] == ["gone", "back"], after
    again = counters(after)
    assert again == sorted(again) and len(set(again)) == len(again), after


def test_processes_reach_a_manager_whose_host_is_not_configured(system: System) -> None:
    """`manager: :PORT` and the manager on a host the configuration does not name (mgr):
    processes on a and b get an address of the manager's host that they reach."""
    system.start_daemons()
    lnc = system.lnc(
        system.process("pub", "a", "pub net.addr nettest/sample --rate 50", "publishing")
        + system.process("sub", "b", "sub net.addr nettest/sample", "subscribed"))
    text = lnc.read_text().replace(f"manager: {system.address}",
                                   f"manager: :{system.address.rpartition(':')[2]}")
    lnc.write_text(text)
    system.run(lnc)
    wait_for(lambda: system.received(system.output("sub")), "b to receive from a")


def test_clients_started_by_hand_on_configured_hosts(system: System) -> None:
    """No process of the configuration runs on another host, but its hosts are named: the
    manager still connects to their daemons, so that programs started there by hand get
    their rings there and their topics forwarded."""
    system.start_daemons()
    mgr = system.start_manager(system.lnc(""))
    pub = system.client("a", "pub", "net.hand", "nettest/sample", "--rate", "50")
    sub = system.client("b", "sub", "net.hand", "nettest/sample")
    assert pub.log_path is not None and sub.log_path is not None
    wait_for(lambda: system.client_received(sub) or pub.poll() is not None
             or sub.poll() is not None, "b to receive from a")
    assert system.client_received(sub), (pub.log_path.read_text()[-2000:],
                                         sub.log_path.read_text()[-2000:])
    assert {h["name"] for h in mgr.hosts()} == {"a", "b", "c"}


def test_a_service_on_the_managers_unconfigured_host_is_called_from_another(
        system: System) -> None:
    """A provider on the manager's host, which the configuration does not name, talks to
    the manager over loopback: a caller on b gets an address of that host it reaches."""
    system.start_daemons()
    lnc = system.lnc(system.process("caller", "b", "call net.mecho --count 3", "calls done"))
    port = system.address.rpartition(":")[2]
    lnc.write_text(lnc.read_text().replace(f"manager: {system.address}", f"manager: :{port}"))
    mgr = system.start_manager(lnc)
    mgr_host = system.lab["mgr"]
    env = system.env(mgr_host)
    env["LN_MANAGER"] = f"127.0.0.1:{port}"
    provider = mgr_host.popen([sys.executable, str(HERE / "netclient.py"), "provide",
                               "net.mecho"], env=env, log="provider.mgr.log")
    system.clients.append(provider)
    wait_for(lambda: "net.mecho" in {s["name"] for s in mgr.services()}, "the provider")
    mgr.start("all")
    mgr.wait_ready("all", timeout=TIMEOUT)
    calls = [line for line in system.output("caller") if line.startswith("call ")]
    assert len(calls) == 3 and all(" OK " in line for line in calls), calls


def test_the_clients_of_a_host_cut_off_are_released(system: System) -> None:
    """c is cut off while a program there publishes: the manager must notice that its
    connection is dead (nothing comes back from a host that is gone) and release its
    ports, as it does for a program that exits."""
    system.start_daemons()
    mgr = system.start_manager(system.lnc(""))
    system.client("c", "pub", "net.cut", "nettest/sample", "--rate", "20")
    wait_for(lambda: "net.cut" in {t["name"] for t in mgr.topics()}, "c's publisher")
    system.lab["c"].disconnect()
    try:
        wait_for(lambda: "net.cut" not in {t["name"] for t in mgr.topics()},
                 "the manager to release the ports of the program on c", timeout=TIMEOUT)
    finally:
        system.lab["c"].reconnect()
