"""What a logger download becomes, on synthetic data: gaps counted from the capture's start
per host, the numpy layout (md fields + seq + publish_time, or opaque bytes for an md this
host lacks), and .npz files that read back exactly."""

from __future__ import annotations

import numpy as np
import pytest

import links_and_nodes as ln
from links_and_nodes import logger_files as lf


@pytest.mark.parametrize(("seqs", "start", "divisor", "dropped", "gaps"), [
    ([11, 12, 13], 10, 1, 0, 0),          # everything after the start
    ([13, 14, 17], 10, 1, 0, 4),          # 11, 12 before the first; 15, 16 between
    ([12, 14, 20], 10, 2, 0, 2),          # kept are the even ones: 16, 18 missing
    ([40, 41, 45], 10, 1, 5, 3),          # evicted ones: count from the oldest kept
    ([11, 12], 12, 1, 0, 0),              # a start read just after the first sample
    ([], 10, 1, 0, 0),
])
def test_gaps_count_missing_kept_samples_from_the_start(seqs, start, divisor, dropped,
                                                        gaps) -> None:
    assert lf.host_gaps(seqs, start, divisor, dropped) == gaps


def test_hosts_are_counted_apart_and_merged_by_time() -> None:
    entry = lf.new_entry("x/none", 1, 4, 1)
    lf.add_host(entry, "a", [(1, 100, b"aaaa"), (3, 300, b"cccc")],
                {"received": 2, "missed": 1, "skipped": 0, "dropped": 0, "start_seq": 0})
    lf.add_host(entry, "b", [(7, 200, b"bbbb")],
                {"received": 1, "missed": 0, "skipped": 0, "dropped": 0, "start_seq": 6})
    assert (entry["gaps"], entry["missed"], entry["hosts"]) == (1, 1, ["a", "b"])


def test_arrays_have_the_md_fields_and_npz_reads_back(tmp_path) -> None:
    cls = ln.message_class("robot/joint_state")
    msgs = []
    for i in (5, 6):
        m = cls()
        m.cycle = i
        m.position[:] = np.arange(7) + i
        msgs.append((i, 1000 * i, bytes(m)))
    entry = lf.new_entry("robot/joint_state", 0x1234, len(msgs[0][2]), 1)
    lf.add_host(entry, "h", msgs, {"received": 2, "missed": 0, "skipped": 0, "dropped": 0,
                                   "start_seq": 4})
    arr = lf.to_array(entry)
    assert list(arr.dtype.names[:2]) == ["seq", "publish_time"]
    assert arr["cycle"].tolist() == [5, 6] and arr["publish_time"].tolist() == [5000, 6000]
    assert np.array_equal(arr["position"][1], np.arange(7) + 6)
    result = lf.save({"arm.state": entry}, tmp_path / "x.npz")
    arrays, meta = lf.load_npz(tmp_path / "x.npz")
    assert np.array_equal(arrays["arm.state"], arr) and meta == result["topics"]
    assert meta["arm.state"]["layout_hash"] == "0000000000001234"
    with pytest.raises(ValueError, match="mcap or .npz"):
        lf.save({"arm.state": entry}, tmp_path / "x.csv")


def test_an_md_this_host_lacks_stays_bytes() -> None:
    entry = lf.new_entry("nowhere/to_be_found", 1, 3, 1)
    lf.add_host(entry, "h", [(1, 1, b"abc")], {"received": 1, "missed": 0, "skipped": 0,
                                               "dropped": 0, "start_seq": 0})
    arr = lf.to_array(entry)
    assert arr.dtype.names == ("seq", "publish_time", "data") and bytes(arr["data"][0]) == b"abc"


def test_fetch_records_round_trip_and_refuse_a_bad_length() -> None:
    samples = [(1, -5, b"xy"), (2, 7, b"zw")]
    assert lf.unpack_samples(lf.pack_samples(samples), 2) == samples
    with pytest.raises(ValueError, match="no multiple"):
        lf.unpack_samples(lf.pack_samples(samples)[:-1], 2)


def test_an_mcap_is_saved_in_ros2_by_default_and_an_npz_in_ln(tmp_path) -> None:
    from links_and_nodes.mcap_format import read_topics
    from links_and_nodes.ros2.types import load_md

    md = load_md("robot/joint_state")
    stats = {"received": 1, "missed": 0, "skipped": 0, "dropped": 0, "start_seq": 0}
    known = lf.new_entry("robot/joint_state", md.layout_hash, md.struct.size, 1)
    lf.add_host(known, "h", [(1, 10, bytes(range(md.struct.size)))], stats)
    unknown = lf.new_entry("nowhere/to_be_found", 1, 3, 1)  # no md here: stays ln
    lf.add_host(unknown, "h", [(1, 1, b"abc")], stats)
    download = {"arm.state": known, "other": unknown}
    result = lf.save(download, tmp_path / "x.mcap")
    assert {t: r["encoding"] for t, r in result["topics"].items()} == {
        "arm.state": "ros2", "other": "ln"}
    topics = read_topics(tmp_path / "x.mcap")
    assert topics["arm.state"].message_encoding == "cdr"
    assert topics["other"].message_encoding == "ln-md"
    assert "encoding" not in lf.save(download, tmp_path / "x.npz")["topics"]["arm.state"]
    with pytest.raises(ValueError, match="'ros2' is for .mcap files"):
        lf.save(download, tmp_path / "y.npz", "ros2")
