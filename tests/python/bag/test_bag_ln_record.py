"""ln_bag on a recording made by a real ln_record (two topics, one importing other mds):
info equals what the PyPI reader reads from the file, a cut, an export of the nested md and
conversions to ln directly and through json agree on every sample."""

from __future__ import annotations

import csv
import json
from pathlib import Path

from record.conftest import Lab
from record.test_record_play import record_two_topics

from bag.conftest import messages, run_bag


def test_ln_bag_on_an_ln_record_file(lab: Lab, tmp_path: Path, capsys) -> None:
    record_two_topics(lab, 600)
    [path] = lab.files()
    original = messages(path)
    capsys.readouterr()
    assert run_bag("info", path, "--json", "-q") == 0
    f = json.loads(capsys.readouterr().out)["files"][0]
    assert f["complete"] and f["messages"] == len(original)
    for t in f["topics"]:
        mine = [(seq, ts) for name, seq, ts, _ in original if name == t["topic"]]
        assert t["count"] == len(mine) and t["gaps"] == 0
        assert (t["first_ns"], t["last_ns"]) == (min(m[1] for m in mine),
                                                 max(m[1] for m in mine))

    times = sorted(m[2] for m in original)
    lo, hi = times[100], times[400]
    out = tmp_path / "cut.mcap"
    assert run_bag("cut", path, "-o", out, "--start", lo, "--end", hi, "-q") == 0
    assert messages(out) == [m for m in original if lo <= m[2] <= hi]

    assert run_bag("export", path, "--csv", tmp_path / "csv", "--topic", "rec.b", "-q") == 0
    with open(tmp_path / "csv" / "rec.b.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == len([m for m in original if m[0] == "rec.b"])
    assert {"tcp.position[2]", "tcp.orientation[3]", "when.sec", "when.nsec"} <= set(rows[0])

    # ln_record's own encoding (ros2 by default) -> ln, and -> json -> ln: the same ln bytes
    ref, mid, back = tmp_path / "ln.mcap", tmp_path / "json.mcap", tmp_path / "back.mcap"
    assert run_bag("convert", path, "-o", ref, "--encoding", "ln", "-q") == 0
    assert run_bag("convert", path, "-o", mid, "--encoding", "json", "-q") == 0
    assert run_bag("convert", mid, "-o", back, "--encoding", "ln", "-q") == 0
    assert [m[:3] for m in messages(ref)] == [m[:3] for m in original]
    assert messages(back) == messages(ref)
    ln_a = [m[3] for m in messages(ref) if m[0] == "rec.a"]
    assert all(len(d) == 32 for d in ln_a)  # rectest/sample's packed size
