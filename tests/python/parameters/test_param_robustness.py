"""Whatever a caller sends a block's service (any op, name and value text: JSON of any shape,
broken JSON, huge numbers, deep nesting, control characters), the controller answers with a
well-formed result or refusal, keeps running, and takes a good value afterwards."""

from __future__ import annotations

import json

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import links_and_nodes as ln

from .conftest import Lab

NAMES = st.sampled_from(["", "kp", "gain", "counter", "label", "mode", "limits", "nope",
                         "kp\x00", "k" * 300])
JSON_VALUES = st.recursive(
    st.none() | st.booleans() | st.integers(min_value=-(2**70), max_value=2**70)
    | st.floats(allow_nan=False) | st.text(max_size=20),
    lambda inner: st.lists(inner, max_size=9) | st.dictionaries(NAMES, inner, max_size=4),
    max_leaves=30)
TEXTS = (JSON_VALUES.map(json.dumps) | st.text(max_size=60)
         | st.sampled_from(["[" * 200, "{\"kp\": " * 100, "1e999999", "-", "\"\\ud800\"",
                            "[1,2,3,4,5,6,7,]", "{\"gain\": 1, }", "\"\\u00\"",
                            "\"a\\nb\"", "{\"gain\": \"x\\ty\"}"]))


def test_any_request_gets_an_answer(lab: Lab) -> None:
    ctl = lab.controller()
    clnt = ln.client("fuzzer", lab.address)
    svc = clnt.get_service(ctl.service, "ln/parameters/query")

    @settings(max_examples=400, deadline=None,
              suppress_health_check=[HealthCheck.function_scoped_fixture])
    @given(op=st.sampled_from(["set", "set", "get", "list", "reset", "bogus", ""]),
           name=NAMES, value=TEXTS)
    def send(op: str, name: str, value: str) -> None:
        svc.req.op = op
        svc.req.name = name
        svc.req.value = value if op != "get" else "{\"wait\": 0}"
        resp = svc.call(timeout=30)
        assert resp.status <= 0
        if resp.status == 0:
            assert resp.error == "" and isinstance(json.loads(resp.result), dict)
        else:
            assert resp.error in ("not_found", "type", "size", "range", "read_only",
                                  "refused", "bad_request")
            assert resp.reason and "\n" not in resp.reason
            assert json.loads(resp.result) == {"parameter": name.split("\x00")[0]}

    try:
        send()
        assert ctl.proc.poll() is None
        svc.req.op, svc.req.name, svc.req.value = "set", "gain", "2"
        assert svc.call(timeout=30).status == 0
        svc.req.op, svc.req.value = "get", ""
        answer = json.loads(svc.call(timeout=30).result)
        (gain,) = [p for p in answer["parameters"] if p["name"] == "gain"]
        assert gain["override"] == 2.0
    finally:
        clnt.close()
