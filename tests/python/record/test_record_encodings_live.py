"""ln_record --encoding ros2 (the default) and json against a manager: the channels are
ros2msg/cdr and jsonschema/json, the PyPI reader with mcap-ros2-support's decoder (and
json.loads) gives the published values, ln_decoder of every sample the published bytes, and
ln_play of such a recording publishes the original samples; an md the encoding refuses is
named and its topic skipped."""

from __future__ import annotations

import ctypes
import json
from pathlib import Path

import pytest

from links_and_nodes.mcap_format import McapReader
from links_and_nodes.record.encodings import ln_decoder

from .conftest import Lab, pypi_mcap, wait_subscribed
from .recording import WAIT, expected, fill, publish, read_all, stop, summary

N = 200


def _packed(md_name: str, numbers: range) -> list[bytes]:
    import links_and_nodes as ln

    cls = ln.message_class(md_name)
    return [ctypes.string_at(ctypes.addressof(m), ctypes.sizeof(m))
            for m in (fill(cls(), i) for i in numbers)]


def _record(lab: Lab, *args: str) -> Path:
    rec = lab.record("enc.a", "enc.b", "enc.s", *args)
    with lab.client("source") as clnt:
        a = clnt.publish("enc.a", "rectest/sample", wait_for_subscribers=True)
        b = clnt.publish("enc.b", "rectest/tool", wait_for_subscribers=True)
        s = clnt.publish("enc.s", "ln/string")  # dynamic field: refused, as with ln
        wait_subscribed(a)
        wait_subscribed(b)
        publish(a, range(N))
        publish(b, range(N))
        assert stop(rec) == 0
        s.close()
    assert summary(lab.log())[:3] == (2 * N, 2, 0), lab.log()
    assert "not recording 'enc.s'" in lab.log() and "dynamic" in lab.log()
    [path] = lab.files()
    return path


@pytest.mark.parametrize("encoding", ["ros2", "json"])
def test_record_in_an_encoding_then_read_and_play(lab: Lab, encoding: str) -> None:
    args = () if encoding == "ros2" else ("--encoding", "json")
    path = _record(lab, *args)
    want = {"enc.a": expected("rectest/sample", range(N)),
            "enc.b": expected("rectest/tool", range(N))}
    raw = {"enc.a": _packed("rectest/sample", range(N)),
           "enc.b": _packed("rectest/tool", range(N))}

    pypi_mcap()
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    got: dict[str, list[object]] = {"enc.a": [], "enc.b": []}
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        if encoding == "ros2":
            for sch, ch, _, msg in reader.iter_decoded_messages():
                assert (sch.encoding, ch.message_encoding) == ("ros2msg", "cdr")
                assert ch.metadata["ros2_type_hash"].startswith("RIHS01_")
                got[ch.topic].append(msg)
            assert [m.counter for m in got["enc.a"]] == list(range(N))
            assert [m.value for m in got["enc.a"]] == [w["value"] for w in want["enc.a"]]
            assert [list(m.values) for m in got["enc.a"]] == [w["values"] for w in want["enc.a"]]
            assert [list(m.tcp.position) for m in got["enc.b"]] == \
                [w["tcp"]["position"] for w in want["enc.b"]]
            assert [m.when.sec for m in got["enc.b"]] == list(range(N))
        else:
            for sch, ch, msg in reader.iter_messages():
                assert (sch.encoding, ch.message_encoding) == ("jsonschema", "json")
                got[ch.topic].append(json.loads(msg.data))
            assert got["enc.a"] == want["enc.a"]
            assert [g["tcp"]["position"] for g in got["enc.b"]] == \
                [w["tcp"]["position"] for w in want["enc.b"]]

    mcap = McapReader(path)
    decoders = {name: ln_decoder(info) for name, info in mcap.topics().items()}
    back: dict[str, list[bytes]] = {"enc.a": [], "enc.b": []}
    for s in mcap:
        back[s.topic].append(decoders[s.topic](s.data))
    assert back == raw

    with lab.client("sink") as clnt:
        sub_a = clnt.subscribe("enc.a", "rectest/sample", buffers=1024)
        sub_b = clnt.subscribe("enc.b", "rectest/tool", buffers=1024)
        played = lab.play("--rate", "1000", "--wait-for-subscribers", str(path),
                          timeout=WAIT)
        assert played.returncode == 0, played.stderr
        got_a = read_all(sub_a, N)
        got_b = read_all(sub_b, N)
    assert [m for _, m in got_a] == want["enc.a"]
    assert [m for _, m in got_b] == want["enc.b"]
