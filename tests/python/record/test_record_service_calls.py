"""`ln_record --services` records calls beside topics into the same files (one channel per
service, docs/recording.md "Service calls"), `ln_play` skips them, and `ln_play --services`
issues them again to the live service."""

from __future__ import annotations

import re
from typing import Any

from polling import wait_for

import links_and_nodes as ln
from links_and_nodes.mcap_format import McapReader
from links_and_nodes.record.service_calls import MESSAGE_ENCODING, STATUS_ERROR, decode_call

from .conftest import Lab, pypi_messages, wait_subscribed
from .recording import publish, stop
from .service_lab import echo_handler, echo_request, echo_response, serving

CALLS = re.compile(r"(\d+) calls of (\d+) services \((\d+) dropped\)")


def test_record_and_play_service_calls(lab: Lab) -> None:
    handled: list[tuple[int, str]] = []

    def handler(request: ln.service_request) -> None:
        handled.append((request.req.seq, request.req.text))
        echo_handler(request)

    prov = lab.client("cli_provider")
    prov.get_service_provider("cli.echo", "lntest/echo", handler)
    prov.get_service_provider("cli.other", "lntest/echo", handler)
    pub = lab.client("cli_pub").publish("cli.topic", "rectest/sample")
    with serving(prov):
        proc = lab.record("cli.topic", "--services", r"cli\.echo")
        wait_for(lambda: "recording the calls of service 'cli.echo'" in lab.log(),
                 "ln_record tapping cli.echo")
        wait_subscribed(pub)
        caller = lab.client("cli_caller")
        svc = caller.get_service("cli.echo", "lntest/echo")
        other = caller.get_service("cli.other", "lntest/echo")
        publish(pub, range(5))
        for seq, text in ((1, "a"), (2, "fail"), (3, "bc")):
            svc.req.caller, svc.req.seq, svc.req.text = 4, seq, text
            try:
                svc.call(timeout=30.0)
            except ln.LnServiceError:
                assert text == "fail"
        other.req.seq, other.req.text = 9, "not recorded"
        other.call(timeout=30.0)
        assert stop(proc) == 0
        log = lab.log()
        assert CALLS.findall(log)[-1] == ("3", "1", "0"), log
        (path,) = lab.files()
        reader = McapReader(path)
        info = reader.topics()["cli.echo"]
        assert "cli.other" not in reader.topics()
        assert (info.kind, info.md_name, info.message_encoding) == (
            "service", "lntest/echo", MESSAGE_ENCODING)
        assert info.layout_hash == ln.message_class("lntest/echo").LAYOUT_HASH
        samples = list(reader.samples(["cli.echo"]))
        calls = [decode_call(s.data, s.topic, info.md_name, info.layout_hash) for s in samples]
        assert [c.request for c in calls] == [echo_request(4, n, t) for n, t in
                                              ((1, b"a"), (2, b"fail"), (3, b"bc"))]
        assert [c.response for c in calls] == [echo_response(4, 1, b"a"), b"",
                                               echo_response(4, 3, b"bc")]
        assert calls[1].status == STATUS_ERROR and calls[1].error == "refused call 2"
        assert {(c.caller, c.provider) for c in calls} == {(caller.name, prov.name)}
        assert [s.publish_time_ns for s in samples] == [c.request_time_ns for c in calls]
        pypi = [m for m in pypi_messages(path) if m[0] == "cli.echo"]
        assert [m[3] for m in pypi] == [s.data for s in samples]

        before = list(handled)
        played = lab.play(str(path))
        assert played.returncode == 0, played.stderr
        assert "published 5 samples" in played.stderr
        assert handled == before  # ln_play alone leaves services alone

        replayed = lab.play("--services", str(path))
        assert replayed.returncode == 0, replayed.stderr
        assert "issued 3 service calls (1 failed)" in replayed.stderr, replayed.stderr
        assert handled[len(before):] == [(1, "a"), (2, "fail"), (3, "bc")]


def test_services_alone_need_no_topics(lab: Lab) -> None:
    prov = lab.client("solo_provider")
    prov.get_service_provider("solo.echo", "lntest/echo", echo_handler)
    with serving(prov):
        proc = lab.record("--services", "solo.echo")
        wait_for(lambda: "recording the calls of service 'solo.echo'" in lab.log(),
                 "ln_record tapping solo.echo")
        svc: Any = lab.client("solo_caller").get_service("solo.echo", "lntest/echo")
        for seq in range(4):
            svc.req.seq, svc.req.text = seq, "x"
            svc.call(timeout=30.0)
        assert stop(proc) == 0
    assert CALLS.findall(lab.log())[-1] == ("4", "1", "0")
    (path,) = lab.files()
    assert len(list(McapReader(path).samples(["solo.echo"]))) == 4
