"""A service provided at site a, called at site b through the two bridges (JSON requests and
responses): dynamic fields both ways (a string, a double array, an array of ln/string), and
the provider's error text reaching the caller."""

from __future__ import annotations

import ast

from zenoh_sites import Site, log_text, start_managers, wait_log


def test_service_call_across_sites_with_dynamic_fields(sites: tuple[Site, Site]) -> None:
    a, b = sites
    start_managers(a, b)
    provider = a.peer("provide", "zb.echo")
    wait_log(provider, "^providing")
    bridge_a = a.bridge("--listen", a.endpoint, "--service-out", "zb.*")
    wait_log(bridge_a, r"service 'zb\.echo' \(zbtest/echo\): served as ln/a/service/zb\.echo")
    bridge_b = b.bridge("--connect", a.endpoint, "--remote", a.prefix,
                        "--service-in", "zb.*,timeout=5")
    ok = b.peer("call", "zb.echo", "hello")
    assert ok.wait(timeout=60) == 0
    line = wait_log(ok, r"^call .*$").group(0)
    assert line.startswith("call OK "), log_text(ok)
    assert ast.literal_eval(line.removeprefix("call OK ")) == {
        "text": "HELLO", "values": [4.5, -6.0, 3e300], "count": 3,
        "words": [{"data": "ahpla"}, {"data": "ateb"}, {"data": "∑ü"}]}
    fail = b.peer("call", "zb.echo", "fail")
    assert fail.wait(timeout=60) == 0
    line = wait_log(fail, r"^call .*$").group(0)
    assert line.startswith("call ERROR LnServiceError") and "asked to fail" in line, line
    stats = b.stats(bridge_b)["services"]["in:zb.echo"]
    assert (stats["calls"], stats["errors"]) == (1, 1)
    stats = a.stats(bridge_a)["services"]["out:zb.echo"]
    assert (stats["calls"], stats["errors"], stats["bad_requests"]) == (1, 1, 0)
    assert "service 'zb.echo': provided here, calls go to ln/a" in log_text(bridge_b)
