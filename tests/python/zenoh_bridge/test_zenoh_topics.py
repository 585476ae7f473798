"""Topics between two links_and_nodes sites (two managers in two network namespaces) through
ln_zenoh: a queued topic arrives whole and in order (site a's bridge started from a .lnc
process section), a latest-mode topic keeps delivering its newest sample through a TCP path
with 20 % injected loss (ln_relay), and a topic whose md has another layout at site b is refused
while another topic keeps flowing.  Every assertion is about what arrived, never how fast."""

from __future__ import annotations

import json
import sys
from pathlib import Path

from netlab import in_netns
from polling import wait_for
from zenoh_sites import MD_CHANGED, MD_DIR, Site, log_text, received, start_managers, wait_log

from links_and_nodes.tools.scripting import connect


def _lnc(site: Site, bridge_args: list[str]) -> Path:
    command = " ".join(site.bridge_argv(*bridge_args))
    path = site.lab.directory / f"{site.name}.lnc"
    path.write_text(f"""instance
name: {site.instance}
manager: 127.0.0.1:{site.address.rsplit(':', 1)[1]}

process zenoh_bridge
    command: {command}
    pass_environment: PYTHONPATH, LN_MESSAGE_DEFINITION_DIRS
    ready_regex: bridge {site.prefix} up
    term_timeout: 5
""")
    return path


def test_queued_topic_arrives_complete_in_order(sites: tuple[Site, Site]) -> None:
    a, b = sites
    a.start_manager("-c", str(_lnc(a, ["--listen", a.endpoint, "--out", "zb.*,queued=512"])),
                    "--daemon-key-file", str(a.lab.key_file), "--start-all", "--wait-ready",
                    wait=False)
    b.start_manager()
    bridge_b = b.bridge("--connect", a.endpoint, "--remote", a.prefix, "--in", "zb.*,queued=512")
    sub = b.peer("sub", "zb.log", "zbtest/sample", "--buffers", "1024")
    wait_log(sub, "^subscribed")
    assert a.manager is not None
    wait_log(a.manager, r"all \d+ processes ready")
    mgr = wait_for(lambda: _connect(a), "site a's manager")
    wait_for(lambda: "remote bridge ln/b is up" in "\n".join(mgr.output("zenoh_bridge", 1000)),
             "site a's bridge (a process of the .lnc) to see site b's")
    a.peer("pub", "zb.log", "zbtest/sample", "--count", "600", "--rate", "2000",
           "--wait-subscribers", "1")
    got = wait_for(lambda: len(r := received(sub)) >= 600 and r, "600 samples at site b")
    assert [counter for _, counter, _ in got] == list(range(1, 601)), "lost or reordered"
    assert all(ok for _, _, ok in got), "a sample's value was damaged"
    seqs = [seq for seq, _, _ in got]
    assert seqs == list(range(seqs[0], seqs[0] + 600)), "gaps in site b's sequence numbers"
    stats = b.stats(bridge_b)["topics"]["in:zb.log"]
    assert (stats["received"], stats["published"], stats["last_seq"]) == (600, 600, 600)
    assert stats["gaps"] == stats["superseded"] == stats["bad_attachment"] == 0
    output = "\n".join(mgr.output("zenoh_bridge", 1000))
    assert "topic 'zb.log' (zbtest/sample, queued): bridged out to ln/a/topic/zb.log" in output
    mgr.close()


def _connect(site: Site) -> object:
    try:
        return in_netns(site.host.netns, lambda: connect(site.address))
    except Exception:  # noqa: BLE001 - not listening yet
        return None


def test_latest_topic_keeps_delivering_the_newest_through_loss(sites: tuple[Site, Site]) -> None:
    a, b = sites
    start_managers(a, b)
    a.bridge("--listen", a.endpoint, "--out", "zb.ctl")
    ready = a.lab.directory / "relay.json"
    stats_file = a.lab.directory / "relay-stats.json"
    relay = b.popen([sys.executable, "-m", "links_and_nodes.relay.cli", "--tcp",
                     "127.0.0.1:17500", f"{a.host.address}:7447", "--loss", "0.2",
                     "--rto-ms", "50", "--rto-max-ms", "400", "--seed", "7", "--ready-file",
                     str(ready), "--stats-file", str(stats_file)], "relay")
    wait_for(ready.exists, "the relay to listen")
    bridge_b = b.bridge("--connect", "tcp/127.0.0.1:17500", "--remote", a.prefix,
                        "--in", "zb.ctl,latest")
    sub = b.peer("sub", "zb.ctl", "zbtest/sample")
    wait_log(sub, "^subscribed")
    a.peer("pub", "zb.ctl", "zbtest/sample", "--count", "600", "--rate", "200",
           "--wait-subscribers", "1")
    wait_for(lambda: (r := received(sub)) and r[-1][1] == 600, "the newest sample (600) at b")
    counters = [counter for _, counter, _ in received(sub)]
    assert counters == sorted(set(counters)), "an older sample came after a newer one"
    assert all(ok for _, _, ok in received(sub))
    stats = b.stats(bridge_b)["topics"]["in:zb.ctl"]
    assert stats["published"] >= len(counters) and stats["last_seq"] == 600
    relay.terminate()
    relay.wait(timeout=30)
    links = json.loads(stats_file.read_text())["links"]
    lost = sum(link[d]["lost"] for link in links for d in ("upstream", "downstream"))
    assert lost > 0, "the relay lost nothing: it was not in the path"


def test_layout_mismatch_is_refused_and_other_topics_flow(sites: tuple[Site, Site]) -> None:
    a, b = sites
    b.md_dirs = [MD_CHANGED, MD_DIR]  # zbtest/sample differs at b, zbtest/other does not
    start_managers(a, b)
    a.bridge("--listen", a.endpoint, "--out", "zb.*")
    bridge_b = b.bridge("--connect", a.endpoint, "--remote", a.prefix, "--in", "zb.*")
    sub = b.peer("sub", "zb.ok", "zbtest/other")
    wait_log(sub, "^subscribed")
    a.peer("pub", "zb.mis", "zbtest/sample", "--rate", "50", "--wait-subscribers", "1")
    a.peer("pub", "zb.ok", "zbtest/other", "--rate", "50", "--wait-subscribers", "1")
    wait_for(lambda: len(received(sub)) >= 20, "zb.ok to flow to b")
    from ln_generate import MdRegistry

    hash_a = MdRegistry([MD_DIR]).load("zbtest/sample").layout_hash
    hash_b = MdRegistry([MD_CHANGED]).load("zbtest/sample").layout_hash
    line = wait_log(bridge_b, r"^ln_zenoh: error: topic 'zb\.mis' .*$").group(0)
    assert f"0x{hash_a:016x}" in line and f"0x{hash_b:016x}" in line, line
    stats = b.stats(bridge_b)["topics"]
    assert stats["in:zb.mis"]["published"] == 0 and stats["in:zb.mis"]["refused"] > 0
    assert stats["in:zb.mis"]["state"].startswith("refused")
    assert stats["in:zb.ok"]["published"] > 0
    assert "zb.mis" not in "".join(line for line in log_text(bridge_b).splitlines()
                                   if "publishing samples" in line)
    seen = received(sub)[-1][1]
    wait_for(lambda: received(sub)[-1][1] > seen + 10, "zb.ok to keep flowing")
