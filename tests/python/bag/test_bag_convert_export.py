"""ln_bag convert: ln -> ros2|json|ln -> ln gives back every sample's bytes; export: the
CSV and npz columns equal the fields of the samples written."""

from __future__ import annotations

import csv
import struct
from pathlib import Path

import numpy as np
import pytest

from bag.conftest import messages, run_bag
from links_and_nodes.mcap_format import McapReader


@pytest.mark.parametrize("encoding", ["ln", "ros2", "json"])
def test_convert_round_trip(tmp_path: Path, two_topics, encoding: str) -> None:
    src, _ = two_topics
    mid, back = tmp_path / f"mid.{encoding}.mcap", tmp_path / "back.mcap"
    assert run_bag("convert", src, "-o", mid, "--encoding", encoding, "-q") == 0
    infos = McapReader(mid).topics()
    expected = {"ln": "ln-md", "ros2": "cdr", "json": "json"}[encoding]
    assert {i.message_encoding for i in infos.values()} == {expected}
    assert all(i.layout_hash == 0x31E316F3DE599ED1 for i in infos.values())
    assert len(messages(mid)) == len(messages(src))
    assert run_bag("convert", mid, "-o", back, "--encoding", "ln", "-q") == 0
    assert messages(back) == messages(src)


def test_convert_names_an_md_it_cannot_encode(tmp_path: Path, two_topics, capsys) -> None:
    src, _ = two_topics
    # a channel whose md text is unusable: its md cannot be built for ros2
    from links_and_nodes.mcap_format import McapWriter

    bad = tmp_path / "bad.mcap"
    with McapWriter(bad) as w:
        ch = w.add_topic("odd", "nosuch/md", b"--- nosuch/md\nfloat99 x\n", 0x1234, 8)
        w.write(ch, 1, 5, b"\0" * 8)
    assert run_bag("convert", bad, "-o", tmp_path / "o.mcap", "--encoding", "ros2") == 1
    err = capsys.readouterr().err
    assert "topic 'odd': md 'nosuch/md' cannot be converted to ros2" in err


def _fields(data: bytes) -> list[float]:
    counter, value, *values = struct.unpack("<Qd4i", data)
    return [counter, value, *values]


def test_export_csv_and_npz(tmp_path: Path, two_topics) -> None:
    src, _ = two_topics
    assert run_bag("export", src, "--csv", tmp_path / "csv", "-q") == 0
    original = messages(src)
    names = ["seq", "publish_time", "counter", "value", "values[0]", "values[1]",
             "values[2]", "values[3]"]
    for topic in ("a.state", "b.cmd"):
        with open(tmp_path / "csv" / f"{topic}.csv", newline="") as f:
            rows = list(csv.reader(f))
        assert rows[0] == names
        expected = [[seq, t, *_fields(d)] for name, seq, t, d in original if name == topic]
        got = [[int(r[0]), int(r[1]), int(r[2]), float(r[3]), *map(int, r[4:])]
               for r in rows[1:]]
        assert got == expected
    npz = tmp_path / "all.npz"
    assert run_bag("export", src, "--npz", npz, "--topic", "b.cmd", "-q") == 0
    with np.load(npz) as f:
        assert sorted(f.files) == ["__topics__", "b.cmd"]
        arr = f["b.cmd"]
    expected = [(seq, t, *_fields(d)) for name, seq, t, d in original if name == "b.cmd"]
    assert list(arr.dtype.names) == names
    assert [tuple(row) for row in arr.tolist()] == expected
    assert run_bag("export", src, "--npz", npz, "-q") == 1  # exists: needs --force
