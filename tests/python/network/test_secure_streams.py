"""Forwarded topics under the instance's `security` level (docs/security.md, "Host-to-host
data"), on separate network stacks: samples arrive intact with `none` and with `encrypt`, and
only `none` shows them on the wire (a capturing relay in front of the receiving daemon); a
daemon whose key was changed is refused by the other (its datagrams and connections counted
as rejected, nothing delivered) until that one has the same key again, without restarting any
client process.  Every assertion is about what arrived or was counted, never how fast."""

from __future__ import annotations

import os
import signal
import sys
from pathlib import Path

import pytest
from polling import wait_for

from .conftest import DAEMON_PORT, HERE, System

TIMEOUT = 60.0
CAPTURE_PORT = 54402


def _with_security(lnc: Path, level: str) -> Path:
    text = lnc.read_text()
    lnc.write_text(text.replace("\nmanager: ", f"\nsecurity: {level}\nmanager: ", 1))
    return lnc


def _plain_windows() -> list[bytes]:
    """Every 32-byte run of netclient.py's blob pattern ((7 i + counter) mod 256): whichever
    sample and offset, the plain bytes contain one of these."""
    cycle = bytes((7 * i) & 0xFF for i in range(256 + 32))
    return [cycle[k:k + 32] for k in range(256)]


def _start_capture(system: System, host: str) -> Path:
    h = system.lab[host]
    out, ready = system.tmp / f"wire-{host}.bin", system.tmp / f"capture-{host}.ready"
    h.popen([sys.executable, str(HERE / "wire_capture.py"), f"{h.address}:{CAPTURE_PORT}",
             f"127.0.0.1:{DAEMON_PORT + 1}", str(out), str(ready), "--cap", str(2 << 20)],
            env=system.env(h), log=f"capture-{host}.log")
    wait_for(ready.exists, "the capturing relay to listen")
    return out


@pytest.mark.parametrize("level", ["none", "encrypt"])
def test_samples_arrive_intact_and_only_none_shows_them_on_the_wire(system: System,
                                                                     level: str) -> None:
    system.start_daemon("a")
    system.start_daemon("b", "--advertise-data-port", str(CAPTURE_PORT))
    wire = _start_capture(system, "b")
    lnc = system.lnc(
        system.process("pub", "a", "pub net.blob nettest/blob --rate 2", "publishing")
        + system.process("sub", "b", "sub net.blob nettest/blob --transport udp",
                         "subscribed"))
    system.run(_with_security(lnc, level))
    try:
        got = wait_for(lambda: len(r := system.received(system.output("sub"))) >= 3 and r,
                       "3 samples of 8 MiB", timeout=TIMEOUT)
    except pytest.fail.Exception:
        pytest.fail(f"no samples: {system.mgr.network()['streams']}, "
                    f"{wire.stat().st_size} bytes captured, {system.output('sub')[-5:]}")
    assert all(ok for _, _, ok in got), f"{level}: corrupt sample"
    assert all(seq == counter for seq, counter, _ in got), got
    wait_for(lambda: wire.stat().st_size >= 2 << 20, "2 MiB through the capturing relay")
    data = wire.read_bytes()
    shown = any(window in data for window in _plain_windows())
    assert shown == (level == "none"), f"{level}: plain sample bytes on the wire: {shown}"
    stream = system.stream("net.blob", "a", "b")
    assert stream is not None and stream["rejected"] == 0, stream


def _write_key(path: Path, hex_key: str) -> None:
    """Replaces a key file the way an operator should: a new file renamed over the old."""
    tmp = path.with_suffix(".new")
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    with os.fdopen(fd, "w") as f:
        f.write(hex_key + "\n")
    os.replace(tmp, path)


def test_a_daemon_with_another_key_is_refused_until_the_keys_match_again(
        system: System) -> None:
    old = system.lab.key_file.read_text().strip()
    keys = {h: system.tmp / f"{h}.key" for h in "ab"}
    for host, path in keys.items():
        _write_key(path, old)
        system.daemons[host] = system.lab[host].start_daemon(path, port=DAEMON_PORT)
    lnc = system.lnc(
        system.process("pub_u", "a", "pub net.ctl nettest/sample --rate 100", "publishing")
        + system.process("pub_t", "a", "pub net.log nettest/sample --rate 100", "publishing")
        + system.process("sub_u", "b", "sub net.ctl nettest/sample --transport udp",
                         "subscribed")
        + system.process("sub_t", "b", "sub net.log nettest/sample --transport tcp "
                         "--buffers 64", "subscribed"))
    system.run(lnc)
    subs = {"sub_u": "net.ctl", "sub_t": "net.log"}

    def count(sub: str) -> int:
        return len(system.received(system.output(sub)))

    def rejected(topic: str) -> int:
        s = system.stream(topic, "a", "b")
        return s["rejected"] if s else 0

    for sub in subs:
        wait_for(lambda sub=sub: count(sub) >= 20, f"{sub} to receive", timeout=TIMEOUT)

    new = os.urandom(32).hex()
    _write_key(keys["a"], new)
    os.kill(system.daemons["a"].pid, signal.SIGHUP)  # only a has the new key now
    for topic in subs.values():
        wait_for(lambda topic=topic: rejected(topic) >= 1, f"b to reject {topic} from a",
                 timeout=TIMEOUT)
    before = {sub: count(sub) for sub in subs}
    seen = {topic: rejected(topic) for topic in subs.values()}
    # a goes on sending (UDP) and connecting (TCP), b goes on refusing: nothing arrives
    for topic in subs.values():
        wait_for(lambda topic=topic: rejected(topic) >= seen[topic] + 3,
                 f"more of {topic} rejected", timeout=TIMEOUT)
    assert {sub: count(sub) for sub in subs} == before

    _write_key(keys["b"], new)
    os.kill(system.daemons["b"].pid, signal.SIGHUP)  # the keys match again
    for sub in subs:
        wait_for(lambda sub=sub: count(sub) >= before[sub] + 20,
                 f"{sub} to receive again after the key change", timeout=TIMEOUT)
