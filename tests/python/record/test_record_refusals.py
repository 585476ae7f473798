"""What ln_play refuses, with a clear one-line error, no traceback and nothing published: a
topic whose md has another layout here or on the manager, a corrupt file, a file cut short
inside a record (unless --partial), a file that is not MCAP."""

from __future__ import annotations

import struct
from pathlib import Path

from links_and_nodes.tools.scripting import connect
from ln_generate import MdRegistry

from .conftest import MD_CHANGED, Lab, wait_subscribed
from .mcap_js import js_rejects
from .recording import chunk_offsets, expected, publish, read_all, stop


def recording(lab: Lab, n: int = 200, *args: str) -> Path:
    rec = lab.record("rec.a", *args)
    with lab.client("source") as clnt:
        pub = clnt.publish("rec.a", "rectest/sample", wait_for_subscribers=True)
        wait_subscribed(pub)
        publish(pub, range(n))
        assert stop(rec) == 0
    [path] = lab.files()
    return path


def topic_names(lab: Lab) -> set[str]:
    with connect(lab.address) as mgr:
        return {t["name"] for t in mgr.topics()}


def refused(done: object) -> str:
    assert done.returncode == 1, done  # type: ignore[attr-defined]
    err: str = done.stderr  # type: ignore[attr-defined]
    assert "Traceback" not in err
    assert len(err.strip().splitlines()) == 1, err
    return err


def test_layout_changed_here_is_refused_naming_md_and_both_hashes(lab: Lab) -> None:
    path = recording(lab)
    import links_and_nodes as ln

    recorded = ln.message_class("rectest/sample").LAYOUT_HASH
    changed = MdRegistry([MD_CHANGED]).load("rectest/sample").layout_hash
    err = refused(lab.play("--remap", "rec.a=play.a", str(path), md_dir=MD_CHANGED))
    assert "'rectest/sample'" in err
    assert f"{recorded:016x}" in err and f"{changed:016x}" in err
    assert "play.a" not in topic_names(lab)  # no publisher was ever made


def test_topic_with_another_layout_on_the_manager_is_refused(lab: Lab) -> None:
    path = recording(lab)
    with lab.client("other") as clnt:
        sub = clnt.subscribe("play.p", "robot/pose", buffers=16)
        err = refused(lab.play("--remap", "rec.a=play.p", str(path)))
        assert "cannot publish topic 'play.p'" in err and "nothing was published" in err
        assert sub.read(timeout=0) is None


def test_corrupt_file_is_refused_with_file_offset_and_reason(lab: Lab) -> None:
    path = recording(lab, 2000, "--chunk-size", "4KiB", "--compression", "lz4")
    data = bytearray(path.read_bytes())
    off, length = chunk_offsets(path)[3]
    data[off + length // 2] ^= 0x55  # inside the compressed records
    path.write_bytes(bytes(data))
    with lab.client("sink") as clnt:
        sub = clnt.subscribe("play.a", "rectest/sample", buffers=16)
        err = refused(lab.play("--remap", "rec.a=play.a", str(path)))
        assert f"ln_play: error: {path}: at byte {off}: Chunk record: " in err
        assert sub.read(timeout=0) is None
    js_rejects(path)  # the independent reader refuses it too


def test_cut_short_file_is_refused_unless_partial(lab: Lab) -> None:
    path = recording(lab, 600, "--chunk-size", "4KiB")  # fewer than the subscriber's buffers
    chunks = chunk_offsets(path)
    off, length = chunks[-2]
    path.write_bytes(path.read_bytes()[:off + length // 2])
    with lab.client("sink") as clnt:
        sub = clnt.subscribe("play.a", "rectest/sample", buffers=1024)
        err = refused(lab.play("--remap", "rec.a=play.a", str(path)))
        assert f"{path}: at byte {off}: truncated: Chunk record of" in err
        assert "--partial" in err
        assert sub.read(timeout=0) is None
        done = lab.play("--partial", "--rate", "100", "--remap", "rec.a=play.a", str(path))
        assert done.returncode == 0, done.stderr
        assert f"is cut short at byte {off}" in done.stderr
        got = read_all(sub, 1)
        while (pkt := sub.read(timeout=0)) is not None:
            got.append((sub.info.timestamp_ns, pkt.to_dict()))
        assert 0 < len(got) < 600
        assert [m for _, m in got] == expected("rectest/sample", range(len(got)))


def test_not_an_mcap_file_and_missing_file(lab: Lab, tmp_path: Path) -> None:
    junk = tmp_path / "junk.mcap"
    junk.write_bytes(b"PK\x03\x04" + bytes(100))
    err = refused(lab.play(str(junk)))
    assert f"{junk}: at byte 0: not an MCAP file" in err
    err = refused(lab.play(str(tmp_path / "missing.mcap")))
    assert "missing.mcap: at byte 0: cannot open: No such file or directory" in err
    empty = tmp_path / "header_only.mcap"
    empty.write_bytes(b"\x89MCAP0\r\n" + struct.pack("<BQ", 1, 8) + bytes(8))
    done = lab.play(str(empty))
    assert done.returncode == 0, done.stderr
    assert "playing 0 samples of 0 topics" in done.stderr
