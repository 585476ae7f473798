"""Record, then play: ln_play reproduces the recorded values in their recorded order, into
other topic names (--remap), into the same names under a fresh manager, from the recorded
definition when the md is not installed, only the chosen topics, from a start offset, and
again and again with --loop."""

from __future__ import annotations

import signal
import subprocess
import sys
import time
import uuid
from pathlib import Path

from polling import sigint_default

import links_and_nodes as ln
from links_and_nodes.manager.frontends import launch
from links_and_nodes.mcap_format import McapReader

from .conftest import Lab, pypi_messages, wait_subscribed
from .mcap_js import js_read
from .recording import expected, publish, read_all, stop, summary


def record_two_topics(lab: Lab, n: int) -> list[tuple[str, int]]:
    """rec.a (rectest/sample) n samples and rec.b (rectest/tool) every third, interleaved;
    the order they were published in as (topic, counter)."""
    rec = lab.record("rec.a", "rec.b")
    order = []
    with lab.client("source") as clnt:
        a = clnt.publish("rec.a", "rectest/sample", wait_for_subscribers=True)
        b = clnt.publish("rec.b", "rectest/tool", wait_for_subscribers=True)
        wait_subscribed(a)
        wait_subscribed(b)
        for i in range(n):
            publish(a, range(i, i + 1))
            order.append(("rec.a", i))
            if i % 3 == 0:
                publish(b, range(i, i + 1))
                order.append(("rec.b", i))
        assert stop(rec) == 0
    return order


def test_record_then_play_reproduces_values_and_order(lab: Lab) -> None:
    n = 3000
    order = record_two_topics(lab, n)
    samples, topics, dropped, files = summary(lab.log())
    assert (samples, topics, dropped, files) == (len(order), 2, 0, 1)
    [path] = lab.files()
    reader = McapReader(path)
    got = [(s.topic, s.seq) for s in reader]
    assert reader.complete
    assert [s for t, s in got if t == "rec.a"] == list(range(1, n + 1))
    assert [s for t, s in got if t == "rec.b"] == list(range(1, len(range(0, n, 3)) + 1))
    assert sorted(m[:2] for m in pypi_messages(path)) == sorted(got)
    assert len(js_read(path)[str(path)]["messages"]) == len(order)

    with lab.client("sink") as clnt:
        sub_a = clnt.subscribe("play.a", "rectest/sample", buffers=1024)
        sub_b = clnt.subscribe("play.b", "rectest/tool", buffers=1024)
        play = subprocess.Popen(
            [sys.executable, "-m", "links_and_nodes.record.play_cli", "--md-dir",
             str(Path(__file__).parent / "md"), "--rate", "1000", "--wait-for-subscribers",
             "--remap", "rec.a=play.a", "--remap", "rec.b=play.b", str(path)],
            env=lab.env(), stderr=subprocess.PIPE, text=True)
        got_a = read_all(sub_a, n)
        got_b = read_all(sub_b, len(range(0, n, 3)))
        _, err = play.communicate(timeout=60)
        assert play.returncode == 0, err
        assert sub_a.overruns == sub_b.overruns == 0
    assert [m for _, m in got_a] == expected("rectest/sample", range(n))
    assert [m for _, m in got_b] == expected("rectest/tool", range(0, n, 3))
    # one player thread wrote them in turn: their new publish times give the played order
    played = sorted([(t, "rec.a", m["counter"]) for t, m in got_a]
                    + [(t, "rec.b", m["counter"]) for t, m in got_b])
    assert [(topic, i) for _, topic, i in played] == order
    assert f"published {len(order)} samples" in err


def test_play_into_the_same_topic_under_a_fresh_manager(lab: Lab, tmp_path: Path) -> None:
    rec = lab.record("rec.a")
    with lab.client("source") as clnt:
        pub = clnt.publish("rec.a", "rectest/sample", wait_for_subscribers=True)
        wait_subscribed(pub)
        publish(pub, range(500))
    assert stop(rec, signal.SIGTERM) == 0
    [path] = lab.files()
    instance = f"f{uuid.uuid4().hex[:8]}"
    fresh = launch.start_manager(instance, tmp_path / "fresh", tmp_path / "fresh.log")
    try:
        with ln.client("sink", fresh.address) as clnt:
            sub = clnt.subscribe("rec.a", "rectest/sample", buffers=1024)
            done = subprocess.run(
                [sys.executable, "-m", "links_and_nodes.record.play_cli", "--manager",
                 fresh.address, "--md-dir", str(Path(__file__).parent / "md"), "--rate", "50",
                 str(path)], capture_output=True, text=True, timeout=120)
            assert done.returncode == 0, done.stderr
            assert [m for _, m in read_all(sub, 500)] == expected("rectest/sample", range(500))
            assert sub.read(timeout=0) is None
    finally:
        assert fresh.stop() == 0
    assert launch.segments(instance) == []


def test_play_uses_the_recorded_definition_of_an_md_not_installed(lab: Lab) -> None:
    rec = lab.record("rec.t")
    with lab.client("source") as clnt:
        pub = clnt.publish("rec.t", "rectest/tool", wait_for_subscribers=True)
        wait_subscribed(pub)
        publish(pub, range(100))
        assert stop(rec) == 0
        sub = clnt.subscribe("play.t", "rectest/tool", buffers=128)
        done = lab.play("--rate", "100", "--remap", "rec.t=play.t", str(lab.files()[0]),
                        md_dir=None)  # neither rectest/tool nor rectest/stamp is found
        assert done.returncode == 0, done.stderr
        assert "md 'rectest/tool' is not installed: using its recorded definition" in done.stderr
        assert [m for _, m in read_all(sub, 100)] == expected("rectest/tool", range(100))


def test_play_only_chosen_topics_from_a_start_offset(lab: Lab) -> None:
    rec = lab.record("rec.a", "rec.b")
    with lab.client("source") as clnt:
        a = clnt.publish("rec.a", "rectest/sample", wait_for_subscribers=True)
        b = clnt.publish("rec.b", "rectest/tool", wait_for_subscribers=True)
        wait_subscribed(a)
        wait_subscribed(b)
        publish(a, range(10))
        publish(b, range(10))
        time.sleep(0.2)  # a gap in the recorded times (its length does not matter)
        publish(a, range(10, 20))
        assert stop(rec) == 0
        [path] = lab.files()
        times = [s.publish_time_ns for s in McapReader(path).samples(["rec.a"])]
        start = (times[10] - 1000 - min(times)) / 1e9  # just before sample 10
        sub_a = clnt.subscribe("play.a", "rectest/sample", buffers=64)
        sub_b = clnt.subscribe("play.b", "rectest/tool", buffers=64)
        done = lab.play("--topics", "rec.a", "--start", f"{start:.9f}", "--rate", "10",
                        "--remap", "rec.a=play.a", "--remap", "rec.b=play.b", str(path))
        assert done.returncode == 1  # rec.b is not played: its --remap is an error
        assert "--remap of topics that are not played: rec.b" in done.stderr
        done = lab.play("--topics", "rec.a", "--start", f"{start:.9f}", "--rate", "10",
                        "--remap", "rec.a=play.a", str(path))
        assert done.returncode == 0, done.stderr
        assert [m for _, m in read_all(sub_a, 10)] == expected("rectest/sample", range(10, 20))
        assert sub_a.read(timeout=0) is None
        assert sub_b.read(timeout=0) is None


def test_loop_plays_again_until_interrupted(lab: Lab) -> None:
    rec = lab.record("rec.a")
    with lab.client("source") as clnt:
        pub = clnt.publish("rec.a", "rectest/sample", wait_for_subscribers=True)
        wait_subscribed(pub)
        publish(pub, range(20))
        assert stop(rec) == 0
        sub = clnt.subscribe("play.a", "rectest/sample", buffers=64)
        play = subprocess.Popen(
            [sys.executable, "-m", "links_and_nodes.record.play_cli", "--md-dir",
             str(Path(__file__).parent / "md"), "--loop", "--rate", "20",
             "--wait-for-subscribers", "--remap", "rec.a=play.a", str(lab.files()[0])],
            env=lab.env(), stderr=subprocess.PIPE, text=True, preexec_fn=sigint_default)
        got = [m["counter"] for _, m in read_all(sub, 50)]
        assert stop(play) == 0  # type: ignore[arg-type]
        assert got == [i % 20 for i in range(50)]
        assert "interrupted after" in (play.stderr.read() if play.stderr else "")
