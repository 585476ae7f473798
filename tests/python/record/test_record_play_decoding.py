"""ln_play's reading of samples: every channel's messages go through its encoding's decoder
to ln bytes before the size check and the publish; a sample that does not decode is refused
naming file, channel and sample; channels that are not topics are not played as topics."""

from __future__ import annotations

import ctypes
from collections.abc import Callable
from pathlib import Path

import pytest

import links_and_nodes as ln
from links_and_nodes.mcap_format import McapWriter, TopicInfo, ln_metadata, md_schema_text
from links_and_nodes.record import player

from .conftest import MD_DIR
from .recording import fill


def write(path: Path, n: int, service_channel: bool = False) -> None:
    cls = ln.message_class("rectest/sample")
    text = md_schema_text("rectest/sample", [str(MD_DIR)])
    with McapWriter(path, compression="none") as w:
        ch = w.add_topic("dec.a", "rectest/sample", text, cls.LAYOUT_HASH, ctypes.sizeof(cls))
        svc = None
        if service_channel:
            svc = w.add_channel("dec.svc", schema_name="rectest/sample",
                                schema_encoding="ln-md-text", schema_data=text,
                                message_encoding="ln-md",
                                metadata=ln_metadata("rectest/sample", cls.LAYOUT_HASH,
                                                     ctypes.sizeof(cls), kind="service"))
        for i in range(n):
            w.write(ch, i + 1, 1000 + i, bytes(fill(cls(), i)))
            if svc is not None:
                w.write(svc, i + 1, 1000 + i, bytes(fill(cls(), 100 + i)))


def failing_at(counter: int, result: Callable[[bytes], bytes]
               ) -> Callable[[TopicInfo], Callable[[bytes], bytes]]:
    """An ln_decoder whose decoder gives result(data) for the sample with that counter."""
    def decoder(info: TopicInfo) -> Callable[[bytes], bytes]:
        def decode(data: bytes) -> bytes:
            if int.from_bytes(data[:4], "little") == counter:
                return result(data)
            return data
        return decode
    return decoder


def boom(data: bytes) -> bytes:
    raise ValueError("bad field 'value'")


def test_every_sample_goes_through_the_decoder(tmp_path: Path,
                                               monkeypatch: pytest.MonkeyPatch) -> None:
    path = tmp_path / "dec.mcap"
    write(path, 5)
    cls = ln.message_class("rectest/sample")
    monkeypatch.setattr(player, "ln_decoder", failing_at(3, lambda d: bytes(fill(cls(), 77))))
    rec = player.check_files([str(path)])
    stored = list(player.stored_samples(rec, ["dec.a"]))
    counters = [cls.from_buffer_copy(player.decode_stored(rec, s).data).counter for s in stored]
    assert counters == [0, 1, 2, 77, 4]


@pytest.mark.parametrize(("result", "why"), [
    (boom, "cannot decode: bad field 'value'"),
    (lambda d: d[:-1], "cannot decode: "),
])
def test_a_sample_that_does_not_decode_names_file_channel_and_sample(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, result: Callable[[bytes], bytes],
        why: str) -> None:
    path = tmp_path / "dec.mcap"
    write(path, 5)
    monkeypatch.setattr(player, "ln_decoder", failing_at(2, result))
    with pytest.raises(player.PlayError) as err:
        player.check_files([str(path)])
    text = str(err.value)
    assert text.startswith(f"{path}: channel 'dec.a' (ln-md), sample 2 of the file "
                           "(sequence 3, time 1002 ns): ")
    assert why in text
    if result is not boom:
        size = ctypes.sizeof(ln.message_class("rectest/sample"))
        assert f"{size - 1} bytes decoded, md 'rectest/sample' has {size}" in text


def test_an_encoding_without_decoder_names_file_and_channel(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    path = tmp_path / "dec.mcap"
    write(path, 1)

    def refuse(info: TopicInfo) -> Callable[[bytes], bytes]:
        raise ValueError(f"topic '{info.topic}': message encoding 'x' is not one ln reads")

    monkeypatch.setattr(player, "ln_decoder", refuse)
    with pytest.raises(player.PlayError, match=rf"^{path}: channel 'dec.a': topic 'dec.a': "):
        player.check_files([str(path)])


def test_channels_that_are_not_topics_are_not_played(tmp_path: Path) -> None:
    path = tmp_path / "dec.mcap"
    write(path, 3, service_channel=True)
    rec = player.check_files([str(path)])
    assert list(rec.topics) == ["dec.a"] and list(rec.others) == ["dec.svc"]
    assert rec.counts == {"dec.a": 3, "dec.svc": 3}
    assert [s.topic for s in player.stored_samples(rec, list(rec.topics))] == ["dec.a"] * 3
