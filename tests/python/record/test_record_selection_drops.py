"""Which topics ln_record records (--all also those that appear later, --regex, a topic it
cannot record said why), --duration, and its count of dropped samples: a recorder that is
stopped (SIGSTOP) while a publisher goes on loses samples to its full queue, and every
published sample is either recorded or counted as dropped."""

from __future__ import annotations

import signal

from polling import wait_for

from links_and_nodes.mcap_format import McapReader

from .conftest import Lab, wait_subscribed
from .recording import publish, stop, summary


def test_drops_are_counted_when_the_recorder_falls_behind(lab: Lab) -> None:
    rec = lab.record("rec.a", "--buffers", "4")
    with lab.client("source") as clnt:
        pub = clnt.publish("rec.a", "rectest/sample")  # never waits for the recorder
        wait_subscribed(pub)
        publish(pub, range(10))
        wait_for(lambda: "recording 'rec.a'" in lab.log(), "ln_record's first line")
        rec.send_signal(signal.SIGSTOP)  # it cannot read now: its 4 buffers fill up
        try:
            publish(pub, range(10, 110))
        finally:
            rec.send_signal(signal.SIGCONT)
        publish(pub, range(110, 120))
        assert stop(rec) == 0
    samples, _, dropped, _ = summary(lab.log())
    [path] = lab.files()
    seqs = [s.seq for s in McapReader(path)]
    assert len(seqs) == samples
    assert dropped > 0  # 100 samples into a queue of a few (the ring may hold some more)
    assert samples + dropped == 120  # each sample recorded or counted, none twice
    assert seqs == sorted(seqs) and seqs[-1] == 120


def test_all_records_topics_that_appear_later(lab: Lab) -> None:
    rec = lab.record("--all")
    with lab.client("source") as clnt:
        early = clnt.publish("rec.early", "rectest/sample", wait_for_subscribers=True)
        wait_subscribed(early)
        publish(early, range(5))
        late = clnt.publish("rec.late", "rectest/tool", wait_for_subscribers=True)
        wait_subscribed(late)
        publish(late, range(7))
        text = clnt.publish("rec.text", "ln/string")
        wait_for(lambda: "not recording 'rec.text'" in lab.log(), "the refusal of rec.text")
        assert text.subscriber_count == 0
        assert stop(rec) == 0
    assert ("not recording 'rec.text': its md 'ln/string' has dynamic fields"
            in lab.log())
    [path] = lab.files()
    reader = McapReader(path)
    assert {t: i.md_name for t, i in reader.topics().items()} == {
        "rec.early": "rectest/sample", "rec.late": "rectest/tool"}
    counts: dict[str, int] = {}
    for sample in reader:
        counts[sample.topic] = counts.get(sample.topic, 0) + 1
    assert counts == {"rec.early": 5, "rec.late": 7}


def test_regex_selects_whole_names_and_duration_ends_a_recording(lab: Lab) -> None:
    with lab.client("source") as clnt:
        pubs = {name: clnt.publish(name, "rectest/sample", wait_for_subscribers=True)
                for name in ("arm.state", "arm.state.raw", "leg.state")}
        rec = lab.record("--regex", r"arm\.[a-z]+", "--regex", "leg.*")
        wait_subscribed(pubs["arm.state"])
        wait_subscribed(pubs["leg.state"])
        for pub in pubs.values():
            publish(pub, range(3))
        assert stop(rec) == 0
        assert pubs["arm.state.raw"].subscriber_count == 0
    assert summary(lab.log()) == (6, 2, 0, 1)
    assert set(McapReader(lab.files()[0]).topics()) == {"arm.state", "leg.state"}
    rec = lab.record("nothing.yet", "--duration", "0.5", "--prefix", "short", log="short.log")
    assert rec.wait(timeout=60) == 0  # ended by itself
    assert summary(lab.log("short.log")) == (0, 0, 0, 1)
    assert McapReader(lab.tmp / "out" / "short_0000.mcap").topics() == {}
