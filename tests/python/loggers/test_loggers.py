"""Topic loggers end to end (docs/logging.md): a C publisher at 1 kHz, the manager placing
the logger on the publisher's host's ln_daemon, and every front end (Python client, C API,
console words through `ln_manager logger`, `.lnc` section) checked on exact sequence
numbers and counters, never on timing."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
from polling import wait_for

import links_and_nodes as ln
from links_and_nodes import logger_files
from links_and_nodes.mcap_format import iter_mcap, read_topics
from links_and_nodes.record.encodings import ln_decoder

TOPIC = "arm.state"


def received(lg: object, at_least: int) -> bool:
    topics = lg.status()["topics"]  # type: ignore[attr-defined]
    return bool(topics) and all(t.get("received", 0) >= at_least for t in topics)


def test_python_logger_keeps_exactly_what_was_published(loglab) -> None:
    loglab.start()
    loglab.publisher(TOPIC)
    lg = loglab.client().get_logger("arm")
    lg.add_topic(TOPIC, 5000)
    lg.enable()
    wait_for(lambda: received(lg, 300), "300 logged samples")
    lg.disable()
    frozen = lg.status()["topics"][0]
    time.sleep(0.2)  # the publisher goes on; a disabled logger must not take any of it
    assert lg.status()["topics"][0]["stored"] == frozen["stored"]
    data = lg.download()[TOPIC]
    assert len(data) == frozen["stored"] == frozen["received"] >= 300
    # every sequence number from the first to the last is there or counted as missed (the
    # logger's ring slack makes misses rare, but a starved daemon thread may have some)
    seqs = data["seq"].astype(np.int64)
    assert len(data) + frozen["missed"] == seqs[-1] - seqs[0] + 1 and frozen["dropped"] == 0
    assert lg.describe()[TOPIC]["gaps"] == frozen["missed"]
    # the md's fields, decoded: the C publisher writes cycle = seq, position[j] = cycle + j/8
    assert np.array_equal(data["cycle"], data["seq"].astype(np.uint32))
    assert np.array_equal(data["position"][:, 3], data["cycle"] + 3 / 8)
    assert np.all(np.diff(data["publish_time"]) >= 0) and np.all(np.diff(seqs) >= 1)


def test_depth_keeps_the_newest_and_counts_what_it_dropped(loglab) -> None:
    loglab.start()
    loglab.publisher(TOPIC)
    lg = loglab.client().get_logger("short")
    lg.add_topic(TOPIC, 100)
    lg.enable()
    wait_for(lambda: received(lg, 350), "350 samples through a 100-deep logger")
    lg.disable()
    st = lg.status()["topics"][0]
    data = lg.download()[TOPIC]
    assert len(data) == st["stored"] == 100
    assert st["dropped"] == st["received"] - 100
    # the newest 100 it received were kept, in order, the misses among them counted
    assert lg.describe()[TOPIC]["gaps"] <= st["missed"]
    assert np.all(np.diff(data["seq"].astype(np.int64)) >= 1)


def test_divisor_keeps_multiples_and_counts_the_rest(loglab) -> None:
    loglab.start()
    loglab.publisher(TOPIC)
    lg = loglab.client().get_logger("every10")
    lg.add_topic(TOPIC, 1000, divisor=10)
    lg.enable()
    wait_for(lambda: received(lg, 300), "300 samples seen")
    lg.disable()
    st = lg.status()["topics"][0]
    data = lg.download()[TOPIC]
    assert len(data) == st["stored"] and np.all(data["seq"] % 10 == 0)
    assert np.all(np.diff(data["seq"].astype(np.int64)) % 10 == 0)
    assert st["skipped"] + st["stored"] == st["received"]
    # the divisor explains every step; only a miss of a multiple of 10 leaves a gap
    assert lg.describe()[TOPIC]["gaps"] <= st["missed"]


def test_a_stalled_daemon_reports_its_gaps_exactly(loglab) -> None:
    """The logger's daemon stopped while the publisher goes on: what it missed is counted,
    and the download's gaps are exactly that count; the publisher never noticed."""
    loglab.start()
    pub = loglab.publisher(TOPIC, 200)
    lg = loglab.client().get_logger("stall")
    lg.add_topic(TOPIC, 100000)
    lg.enable()
    wait_for(lambda: received(lg, 100), "100 samples before the stall")
    daemons = loglab.lab.daemon_pids()
    assert daemons
    os.kill(daemons[0], signal.SIGSTOP)
    try:
        time.sleep(0.5)  # the ring has far fewer slots than the samples published meanwhile
    finally:
        os.kill(daemons[0], signal.SIGCONT)
    before = lg.status()["topics"][0]["received"]
    wait_for(lambda: received(lg, before + 100), "samples after the stall")
    lg.disable()
    st = lg.status()["topics"][0]
    assert st["missed"] > 0 and st["dropped"] == 0
    lg.download()
    assert lg.describe()[TOPIC]["gaps"] == st["missed"]
    assert pub.poll() is None


def test_over_the_memory_limit_is_refused_and_others_keep_logging(loglab) -> None:
    loglab.start()
    loglab.publisher(TOPIC)
    clnt = loglab.client()
    good = clnt.get_logger("good")
    good.add_topic(TOPIC, 1000)
    good.enable()
    huge = clnt.get_logger("huge")
    with pytest.raises(ln.LnLimitError) as err:
        huge.add_topic(TOPIC, 1 << 28)
    assert "memory" in str(err.value) and TOPIC in str(err.value)
    assert huge.status()["patterns"] == []  # nothing of the refused request stayed
    base = good.status()["topics"][0]["received"]
    wait_for(lambda: received(good, base + 100), "the other logger going on")


def test_unknown_logger_and_bad_arguments_are_clear_errors(loglab) -> None:
    loglab.start()
    clnt = loglab.client()
    with pytest.raises(ln.LnNotfoundError, match="no logger 'nope'"):
        clnt.control("logger_status", name="nope")
    lg = clnt.get_logger("x")
    with pytest.raises(ln.LnInvalError, match="depth"):
        lg.add_topic(TOPIC, 0)
    with pytest.raises(ln.LnInvalError, match="bad logger name"):
        clnt.get_logger("a b")
    lg.add_topic("no.publisher.yet", 10)  # fine: placed once a publisher comes
    assert lg.status()["topics"] == []


def test_topic_appearing_later_and_c_api_and_manager_side_save(loglab, tmp_path) -> None:
    loglab.start()
    out = loglab.run_tool("logger_tool", "c_api", "late.*", "5000", "1", "start")
    assert out.stdout.strip() == "ok", out.stdout + out.stderr
    loglab.publisher("late.topic")
    clnt = loglab.client()
    lg = clnt.get_logger("c_api")
    assert lg.status()["enabled"]
    wait_for(lambda: received(lg, 200), "the topic that came after the logger")
    path = tmp_path / "c_api.npz"
    out = loglab.run_tool("logger_tool", "c_api", "-", "0", "0", "stop", str(path))
    assert out.stdout.strip() == "ok", out.stdout + out.stderr
    arrays, meta = logger_files.load_npz(path)
    data = arrays["late.topic"]
    assert meta["late.topic"]["samples"] == len(data) >= 200
    assert meta["late.topic"]["gaps"] == meta["late.topic"]["missed"]
    assert np.array_equal(data["cycle"], data["seq"].astype(np.uint32))
    # an .mcap from the C API gets the default encoding, ros2, and decodes to the same samples
    mcap = tmp_path / "c_api.mcap"
    out = loglab.run_tool("logger_tool", "c_api", "-", "0", "0", "stop", str(mcap))
    assert out.stdout.strip() == "ok", out.stdout + out.stderr
    info = read_topics(mcap)["late.topic"]
    assert info.message_encoding == "cdr"
    to_ln = ln_decoder(info)
    got = [(s.seq, s.publish_time_ns, to_ln(s.data)) for s in iter_mcap(mcap)]
    assert [seq for seq, _, _ in got] == data["seq"].tolist()
    assert got == lg.download_raw()["late.topic"]["samples"]
    refused = loglab.run_tool("logger_tool", "c_api", "late.*", "0", "1", "add")
    assert refused.returncode == 1 and "EINVAL" in refused.stdout


def test_lnc_logger_section_autostarts_and_cli_saves(loglab, tmp_path) -> None:
    loglab.start("logger boot\nautostart: true\narm.*: depth:2000, divisor:2\n")
    loglab.publisher(TOPIC)
    status = loglab.cli("logger", "boot", "status", "--json")
    assert status.returncode == 0, status.stderr
    wait_for(lambda: received(loglab.client().get_logger("boot"), 200), "autostarted logging")
    text = loglab.cli("logger", "boot", "status")
    assert "logger boot: enabled; arm.* (depth 2000, divisor 2)" in text.stdout
    assert TOPIC in text.stdout
    assert loglab.cli("logger", "boot", "disable").returncode == 0
    path = tmp_path / "boot.npz"
    saved = loglab.cli("logger", "boot", "save", str(path))
    assert saved.returncode == 0, saved.stderr
    arrays, meta = logger_files.load_npz(path)
    assert np.all(arrays[TOPIC]["seq"] % 2 == 0)
    assert meta[TOPIC]["gaps"] <= meta[TOPIC]["missed"]
    listing = loglab.cli("logger")
    assert "boot" in listing.stdout and "no" in listing.stdout  # disabled now
    bad = loglab.cli("logger", "boot", "frobnicate")
    assert bad.returncode == 2 and "usage: logger" in bad.stderr
    missing = loglab.cli("logger", "nope", "status")
    assert missing.returncode == 1 and "no logger 'nope'" in missing.stderr


def test_a_saved_mcap_holds_the_download_and_ln_play_reads_it(loglab, tmp_path) -> None:
    loglab.start()
    loglab.publisher(TOPIC)
    lg = loglab.client().get_logger("tomcap")
    lg.add_topic(TOPIC, 500)
    lg.enable()
    wait_for(lambda: received(lg, 100), "100 samples")
    lg.disable()
    raw = lg.download_raw()[TOPIC]
    local = tmp_path / "here.mcap"
    assert lg.save(local)["topics"][TOPIC]["encoding"] == "ros2"  # the default
    remote = tmp_path / "on_manager.mcap"
    saved = lg.save_on_manager(str(remote))["topics"][TOPIC]
    assert (saved["samples"], saved["encoding"]) == (len(raw["samples"]), "ros2")
    bitwise = tmp_path / "raw.mcap"
    assert lg.save(bitwise, encoding="ln")["topics"][TOPIC]["encoding"] == "ln"
    remote_raw = tmp_path / "on_manager_raw.mcap"
    assert lg.save_on_manager(str(remote_raw), "ln")["topics"][TOPIC]["encoding"] == "ln"
    for path, encoding in [(local, "cdr"), (remote, "cdr"), (bitwise, "ln-md"),
                           (remote_raw, "ln-md")]:
        info = read_topics(path)[TOPIC]
        assert (info.md_name, info.layout_hash) == ("robot/joint_state", raw["layout_hash"])
        assert info.message_encoding == encoding, path
        assert b"position" in info.md_text  # the md itself travels with the file
        to_ln = ln_decoder(info) if encoding == "cdr" else bytes
        got = [(s.seq, s.publish_time_ns, to_ln(s.data)) for s in iter_mcap(path)]
        assert got == raw["samples"]
    # ln_play publishes the capture again, value for value, in order
    sub = lg.clnt.subscribe("replayed.state", "robot/joint_state", buffers=len(raw["samples"]))
    play = subprocess.run([sys.executable, "-m", "links_and_nodes.record.play_cli", str(local),
                           "--remap", f"{TOPIC}=replayed.state", "--rate", "100", "-q"],
                          env=loglab.env, capture_output=True, text=True, timeout=60)
    assert play.returncode == 0, play.stderr
    cycles = []
    while (msg := sub.read(timeout=0)) is not None:
        cycles.append(msg.cycle)
    assert cycles == [seq for seq, _, _ in raw["samples"]]
    with pytest.raises(ln.LnInvalError, match="absolute path"):
        lg.clnt.control("logger_save", name="tomcap", path="relative.mcap")


def test_a_manager_takes_over_the_loggers_its_predecessor_left(loglab) -> None:
    """A manager that dies (or detaches) leaves the loggers and their samples in the daemon;
    the next manager of the instance adopts them by name (a manager that quits removes
    them)."""
    loglab.start()
    loglab.publisher(TOPIC)
    lg = loglab.client("first").get_logger("kept")
    lg.add_topic(TOPIC, 20000)
    lg.enable()
    wait_for(lambda: received(lg, 200), "samples before the detach")
    lg.disable()
    before = lg.download_raw()[TOPIC]["samples"]
    proc = loglab.lab.managers[-1]
    proc.kill()
    proc.wait(timeout=60)
    loglab.start("", "--adopt-window", "5")  # the publisher's ring is taken over too
    lg2 = loglab.client("second").get_logger("kept")
    st = lg2.status()
    assert not st["enabled"] and [p["pattern"] for p in st["patterns"]] == [TOPIC]
    assert lg2.download_raw()[TOPIC]["samples"][:len(before)] == before
    lg2.enable()  # and it goes on logging the publisher, which reconnected
    wait_for(lambda: received(lg2, 100), "samples under the new manager")
