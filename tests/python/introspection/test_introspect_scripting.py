"""Live introspection in the scripting API (`links_and_nodes.manager.connect`): the methods
return Python values for known data, and raise ManagerError with the one-line text for
every failure."""

from __future__ import annotations

import pytest

import links_and_nodes as ln
from links_and_nodes.manager import connect
from links_and_nodes.tools.scripting import ManagerError

from .adjust_provider import adjust
from .conftest import LIMIT, MDS, Lab
from .probe_publisher import probe_values


def test_topic_echo_returns_decoded_samples(lab: Lab) -> None:
    lab.publisher()
    with connect(lab.address, timeout=LIMIT) as mgr:
        records = mgr.topic_echo("probe.state", n=3, timeout=LIMIT)
        fields = mgr.topic_echo("probe.state", n=2, field="target.position", timeout=LIMIT)
    assert len(records) == 3
    assert [r["seq"] for r in records] == sorted({r["seq"] for r in records})
    for record in records:
        assert record["data"] == probe_values(record["seq"])
        assert record["publish_time_ns"] > 0
    for record in fields:
        k = record["seq"]
        assert (record["field"], record["data"]) == ("target.position", [k, 2 * k, 3 * k])


def test_topic_echo_returns_what_came_within_the_timeout(lab: Lab) -> None:
    ln.add_message_definition_dir(MDS)
    clnt = ln.client("silent", lab.address)
    try:
        pub = clnt.publish("probe.silent", "lntest/probe")
        with connect(lab.address, timeout=LIMIT) as mgr:
            assert mgr.topic_echo("probe.silent", n=5, timeout=0.3) == []
            pub.packet.count = 7
            pub.write()
            # a new subscriber gets the newest sample there is, then nothing more comes
            [record] = mgr.topic_echo("probe.silent", n=5, timeout=0.3)
    finally:
        clnt.close()
    assert (record["seq"], record["data"]["count"]) == (1, 7)


def test_topic_hz_and_bw_return_statistics_of_n_samples(lab: Lab) -> None:
    lab.publisher()
    with connect(lab.address, timeout=LIMIT) as mgr:
        hz = mgr.topic_hz("probe.state", duration=None, n=5)
        bw = mgr.topic_bw("probe.state", duration=None, n=5)
    for stats in (hz, bw):
        assert stats["samples"] == 5
        assert stats["periods"] + stats["missed"] >= 4 and stats["periods"] <= 4
        assert stats["rate_hz"] > 0
        if stats["periods"]:
            assert stats["min_s"] <= stats["mean_s"] <= stats["max_s"]
    assert bw["message_size"] == 940
    assert bw["bytes_per_s"] == pytest.approx(940 * bw["rate_hz"])
    with connect(lab.address) as mgr, pytest.raises(ValueError):
        mgr.topic_hz("probe.state", duration=None)


def test_topic_info_md_show_and_service_call(lab: Lab) -> None:
    pub = lab.publisher()
    lab.provider()
    request = {"values": [1, 2, 3], "offset": 4, "name": "n", "tags": ["x", "y"],
               "target": {"position": [1, 1, 1]}}
    with connect(lab.address, timeout=LIMIT) as mgr:
        info = mgr.topic_info("probe.state")
        text = mgr.md_show("lntest/probe")
        response = mgr.service_call("probe.adjust", request)
        from_text = mgr.service_call("probe.adjust", "values: [1, 2, 3], offset: 4")
    assert (info["md_name"], info["message_size"]) == ("lntest/probe", 940)
    assert [p["pid"] for p in info["publishers"]] == [pub.pid]
    assert str(MDS) in info["md_dirs"]
    assert text == (MDS / "lntest" / "probe").read_text()
    assert response == adjust({**request, "tags": [{"data": "x"}, {"data": "y"}],
                               "target": {"position": [1, 1, 1],
                                          "orientation": [0.0] * 4}})
    assert from_text["total"] == 10.0


@pytest.mark.parametrize(("call", "error"), [
    (lambda m: m.topic_info("nope"), "no topic 'nope'"),
    (lambda m: m.topic_echo("nope"), "no topic 'nope'"),
    (lambda m: m.topic_hz("nope"), "no topic 'nope'"),
    (lambda m: m.md_show("lntest/nope"), "message definition 'lntest/nope' not found"),
    (lambda m: m.service_call("nope", {}), "no service 'nope'"),
    (lambda m: m.service_call("probe.adjust", "a b"),
     "bad request text at column 3: expected ':' after 'a', found 'b'"),
    (lambda m: m.service_call("probe.adjust", {"offset": "x"}),
     "field 'offset': expected an integer (int32_t), not the string 'x'"),
    (lambda m: m.service_call("probe.adjust", {"name": "fail"}),
     "service 'probe.adjust' (provider 'adjuster') answered with an error: asked to fail"),
    (lambda m: m.topic_echo("probe.state", field="nope"),
     "topic 'probe.state': md 'lntest/probe' has no field 'nope'"),
])
def test_errors_raise_manager_error(lab: Lab, call: object, error: str) -> None:
    lab.publisher()
    lab.provider()
    with connect(lab.address, timeout=LIMIT) as mgr:
        with pytest.raises(ManagerError) as info:
            call(mgr)  # type: ignore[operator]
        assert str(info.value).startswith(error)
        assert "\n" not in str(info.value)
        assert mgr.topics()  # the connection goes on
