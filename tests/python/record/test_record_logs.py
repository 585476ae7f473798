"""ln_record --logs (docs/recording.md, "Log lines"): the manager's log lines of every client
go into the recording as foxglove.Log messages in JSON on channel `ln.log` (schema encoding
jsonschema), with level, time, process@host and file:line, so Foxglove's Log panel shows
them; the files stay valid for our reader (which skips the channel: it has no ln md) and
for the PyPI reader, which reads the messages back."""

from __future__ import annotations

import json
import logging
import signal
import sys

from polling import wait_for

import links_and_nodes as ln
from links_and_nodes.mcap_format import McapReader
from links_and_nodes.tools import scripting

from .conftest import Lab, pypi_messages, pypi_stream


def test_log_lines_recorded_as_foxglove_log(lab: Lab) -> None:
    rec = lab.record("--logs")
    wait_for(lambda: "recording the manager's log lines" in lab.log(), "ln_record's start")
    clnt = ln.client("arm_ctl", lab.address)
    logger = logging.getLogger("test.record.logs")
    logger.propagate = False
    logger.setLevel(logging.DEBUG)
    handler = ln.LogHandler(clnt)
    logger.addHandler(handler)
    try:
        first = sys._getframe().f_lineno + 1
        logger.warning("joint 3 near its limit")
        logger.error("arm fault %d", 7)
        handler.flush(60.0)
    finally:
        logger.removeHandler(handler)
        clnt.close()
    with scripting.connect(lab.address) as mgr:
        assert len(mgr.log(process="arm_ctl")) == 2  # the manager has them
    rec.send_signal(signal.SIGINT)
    assert rec.wait(timeout=120) == 0, lab.log()
    assert "2 log lines" in lab.log()
    [path] = lab.files()
    reader = McapReader(path)
    assert list(reader.samples()) == [] and reader.complete  # checked whole, CRCs included
    records, complete = pypi_stream(path)  # skips (or fails in CI) without PyPI mcap
    assert complete
    from mcap.records import Channel, Schema

    # (each record is in the data section and again in the summary)
    [channel] = {r.id: r for r in records if isinstance(r, Channel)}.values()
    [schema] = {r.id: r for r in records
                if isinstance(r, Schema) and r.id == channel.schema_id}.values()
    assert (channel.topic, channel.message_encoding) == ("ln.log", "json")
    assert (schema.name, schema.encoding) == ("foxglove.Log", "jsonschema")
    properties = json.loads(schema.data)["properties"]
    assert set(properties) == {"timestamp", "level", "message", "name", "file", "line"}
    messages = [json.loads(data) for topic, _, _, data in pypi_messages(path)]
    assert [(m["level"], m["message"]) for m in messages] == [
        (3, "joint 3 near its limit"), (4, "arm fault 7")]
    for m, line in zip(messages, (first, first + 1), strict=True):
        assert m["name"].startswith("arm_ctl@") and m["file"] == __file__ and m["line"] == line
        assert set(m["timestamp"]) == {"sec", "nsec"} and 0 <= m["timestamp"]["nsec"] < 10**9
    times = [t for _, _, t, _ in pypi_messages(path)]
    assert times == [m["timestamp"]["sec"] * 10**9 + m["timestamp"]["nsec"] for m in messages]
