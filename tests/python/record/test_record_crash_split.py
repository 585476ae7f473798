"""What ln_record leaves behind: after a SIGKILL a file without summary that the PyPI `mcap`
stream reader, @mcap/core and our reader all read up to its last complete chunk, and that
ln_play plays; with --split-size several files, each complete and valid on its own, that
together hold every sample in order."""

from __future__ import annotations

import signal
from pathlib import Path

from polling import wait_for

from links_and_nodes.mcap_format import McapReader, iter_mcap

from .conftest import Lab, pypi_mcap, pypi_messages, pypi_stream, wait_subscribed
from .mcap_js import js_read
from .recording import expected, publish, read_all, stop, summary


def recorded(path: Path) -> int:
    return sum(1 for _ in iter_mcap(path))


def test_sigkill_leaves_a_file_readable_up_to_its_last_complete_chunk(lab: Lab) -> None:
    rec = lab.record("rec.a", "--chunk-size", "4KiB", "--flush-interval", "0.1")
    with lab.client("source") as clnt:
        pub = clnt.publish("rec.a", "rectest/sample", wait_for_subscribers=True)
        wait_subscribed(pub)
        publish(pub, range(500))
        wait_for(lambda: lab.files() and recorded(lab.files()[0]) == 500,
                 "the first 500 samples in complete chunks")
        publish(pub, range(500, 520))  # some of these may be in the open chunk
        rec.send_signal(signal.SIGKILL)
        assert rec.wait() == -signal.SIGKILL
    [path] = lab.files()
    reader = McapReader(path, allow_truncated=True)
    ours = [(s.topic, s.seq, s.publish_time_ns, s.data) for s in reader]
    assert not reader.complete  # no summary, no footer
    k = len(ours)
    assert 500 <= k <= 520
    assert [s[1] for s in ours] == list(range(1, k + 1))
    assert ours == pypi_messages(path)  # the PyPI stream reader: the same, then end of file
    _, done = pypi_stream(path)
    assert not done
    js = js_read(path)[str(path)]
    assert not js["done"] and "indexed" not in js
    assert [(t, s, int(p), bytes.fromhex(d)) for t, s, p, _, d in js["messages"]] == ours

    with lab.client("sink") as clnt:
        sub = clnt.subscribe("play.a", "rectest/sample", buffers=1024)
        done = lab.play("--rate", "100", "--remap", "rec.a=play.a", str(path))
        assert done.returncode == 0, done.stderr
        assert "has no summary (its recorder did not close it)" in done.stderr
        assert [m for _, m in read_all(sub, k)] == expected("rectest/sample", range(k))


def test_split_size_gives_several_complete_files(lab: Lab) -> None:
    n = 3000
    rec = lab.record("rec.a", "--split-size", "64KiB", "--chunk-size", "8KiB",
                     "--compression", "none", "--prefix", "split")
    with lab.client("source") as clnt:
        pub = clnt.publish("rec.a", "rectest/sample", wait_for_subscribers=True)
        wait_subscribed(pub)
        publish(pub, range(n))
        assert stop(rec) == 0
    files = lab.files()
    assert [p.name for p in files] == [f"split_{i:04d}.mcap" for i in range(len(files))]
    assert len(files) >= 3
    assert summary(lab.log()) == (n, 1, 0, len(files))
    pypi_mcap()
    from mcap.reader import make_reader

    seqs = []
    for path in files:
        reader = McapReader(path)
        seqs += [s.seq for s in reader]
        assert reader.complete
        assert list(reader.topics()) == ["rec.a"]
        assert path.stat().st_size < 64 * 1024 + 8 * 1024 + 4096  # split + a chunk + summary
        with open(path, "rb") as f:
            indexed = make_reader(f)
            counts = indexed.get_summary().statistics.message_count
            assert counts == sum(1 for _ in indexed.iter_messages())
        js = js_read(path)[str(path)]
        assert js["done"] and js["indexed"]["messages"] == js["indexed"]["statistics"] == counts
    assert seqs == list(range(1, n + 1))
