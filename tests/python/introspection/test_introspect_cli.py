"""`ln_manager topic echo|hz|bw|info`, `md show`, `service call` as client processes of a
real manager, against a publisher process of known values and a provider process: what they
print for known data, and a one-line error with exit status 1 for every failure."""

from __future__ import annotations

import json
import re
import signal
import subprocess
import sys
from typing import Any

import pytest
from polling import sigint_default, wait_for

import links_and_nodes as ln
from links_and_nodes.tools.introspection.client import load_md

from .adjust_provider import adjust
from .conftest import MDS, OTHER_MDS, Lab
from .probe_publisher import probe_values

HEADER = re.compile(r"^--- seq (\d+), published (\d+)\.(\d{9})$")
HZ = re.compile(r"^rate: ([0-9.]+) Hz  mean: .+  min: .+  max: .+  std dev: .+  "
                r"window: (\d+) samples, (\d+) periods, (\d+) missed$")


def probe_hash() -> int:
    return load_md("lntest/probe", [str(MDS)]).layout_hash


def blocks(out: str) -> list[tuple[int, list[str]]]:
    """(seq, lines) of each sample `topic echo` printed."""
    result: list[tuple[int, list[str]]] = []
    for line in out.splitlines():
        match = HEADER.match(line)
        if match:
            result.append((int(match.group(1)), []))
        else:
            assert result, f"output does not start with a header: {out!r}"
            result[-1][1].append(line)
    return result


def expected_lines(k: int) -> list[str]:
    trace = ", ".join(f"{k * 1000 + i}.0" for i in range(8))
    return [f"count: {k}",
            "q: [" + ", ".join(repr(k + j / 8) for j in range(7)) + "]",
            "target:", f"  position: [{k}.0, {2 * k}.0, {3 * k}.0]",
            "  orientation: [0.0, 0.0, 0.0, 1.0]",
            "gains: [0.1, 0.2, 0.3]", 'label: "probe"',
            f"trace: [{trace}, ... (100 values)]"]


def one_error(done: Any, command: str) -> str:
    """The error of a failed command: exit 1, nothing on stdout, one line on stderr."""
    assert done.returncode == 1, (done.stdout, done.stderr)
    assert done.stdout == ""
    lines = done.stderr.splitlines()
    assert len(lines) == 1, done.stderr
    assert lines[0].startswith(f"ln_manager {command}: error: "), lines[0]
    return lines[0].removeprefix(f"ln_manager {command}: error: ")


# ---- topic echo --------------------------------------------------------------------------
def test_echo_prints_n_samples_decoded_by_the_md(lab: Lab) -> None:
    lab.publisher()
    done = lab.ln_manager("topic", "echo", "probe.state", "-n", "3")
    assert done.returncode == 0, done.stderr
    samples = blocks(done.stdout)
    assert len(samples) == 3
    seqs = [seq for seq, _ in samples]
    assert seqs == sorted(set(seqs))
    for seq, lines in samples:  # the only publisher: sample k is sequence number k
        assert lines == expected_lines(seq)


def test_echo_full_prints_every_value(lab: Lab) -> None:
    lab.publisher()
    done = lab.ln_manager("topic", "echo", "probe.state", "-n", "1", "--full")
    assert done.returncode == 0, done.stderr
    [(seq, lines)] = blocks(done.stdout)
    trace = next(line for line in lines if line.startswith("trace: "))
    assert trace == "trace: [" + ", ".join(f"{seq * 1000 + i}.0" for i in range(100)) + "]"


@pytest.mark.parametrize(("path", "value"), [
    ("count", lambda k: k),
    ("q[2]", lambda k: k + 2 / 8),
    ("q", lambda k: [k + j / 8 for j in range(7)]),
    ("target.position[1]", lambda k: 2.0 * k),
    ("label", lambda k: "probe"),
    ("gains[0]", lambda k: 0.1),
])
def test_echo_field_json_holds_that_value_of_each_sample(lab: Lab, path: str,
                                                         value: Any) -> None:
    lab.publisher()
    done = lab.ln_manager("topic", "echo", "probe.state", "--field", path, "-n", "2", "--json")
    assert done.returncode == 0, done.stderr
    records = [json.loads(line) for line in done.stdout.splitlines()]
    assert len(records) == 2
    for record in records:
        assert record["field"] == path
        assert record["data"] == value(record["seq"])


def test_echo_field_prints_only_the_value(lab: Lab) -> None:
    lab.publisher()
    for path, check in [
        ("label", lambda line: line == '"probe"'),
        ("gains", lambda line: line == "[0.1, 0.2, 0.3]"),
        ("q[2]", lambda line: (float(line) - 0.25).is_integer() and float(line) > 1),
        ("count", lambda line: line.isdigit()),
    ]:
        done = lab.ln_manager("topic", "echo", "probe.state", "--field", path, "-n", "3")
        assert done.returncode == 0, done.stderr
        lines = done.stdout.splitlines()
        assert len(lines) == 3 and all(check(line) for line in lines), (path, lines)


def test_echo_field_of_a_message_prints_a_block(lab: Lab) -> None:
    lab.publisher()
    done = lab.ln_manager("topic", "echo", "probe.state", "--field", "target", "-n", "1")
    assert done.returncode == 0, done.stderr
    [(seq, lines)] = blocks(done.stdout)
    assert lines == [f"position: [{seq}.0, {2 * seq}.0, {3 * seq}.0]",
                     "orientation: [0.0, 0.0, 0.0, 1.0]"]


def test_echo_json_prints_one_object_per_line_with_full_values(lab: Lab) -> None:
    lab.publisher()
    done = lab.ln_manager("topic", "echo", "probe.state", "-n", "2", "--json")
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert len(lines) == 2
    for line in lines:
        record = json.loads(line)
        assert set(record) == {"seq", "publish_time", "publish_time_ns", "data"}
        assert record["data"] == probe_values(record["seq"])  # every trace value, too
        assert record["publish_time"] == pytest.approx(record["publish_time_ns"] / 1e9)


def test_echo_and_hz_attach_without_making_a_waiting_publisher_wait(lab: Lab) -> None:
    """A publisher that waits for its subscribers keeps writing with timeout 0 while an
    introspection subscriber is attached and does not read: it is in latest mode."""
    from links_and_nodes.tools.introspection.client import TopicReader

    clnt = ln.client("waiter", lab.address)
    ln.add_message_definition_dir(MDS)
    try:
        pub = clnt.publish("probe.wait", "lntest/probe", wait_for_subscribers=True)
        cls = pub.message_class
        with TopicReader(lab.address, "ln_topic_echo", "probe.wait", "lntest/probe",
                         cls.LAYOUT_HASH, ctypes_size(cls)):
            for k in range(1, 200):
                pub.packet.count = k
                pub.write(timeout=0)  # LnTimeoutError if it had to wait
            done = lab.ln_manager("topic", "info", "probe.wait", "--json")
        info = json.loads(done.stdout)
        [sub] = info["subscribers"]
        assert (sub["client"], sub["mode"], sub["buffers"]) == ("ln_topic_echo", "latest", 1)
        assert info["publishers"][0]["wait_for_subscribers"] is True
    finally:
        clnt.close()


def ctypes_size(cls: type) -> int:
    import ctypes

    return ctypes.sizeof(cls)


# ---- topic hz / bw -----------------------------------------------------------------------
def test_hz_with_n_prints_a_rate_line_over_n_samples(lab: Lab) -> None:
    lab.publisher()
    done = lab.ln_manager("topic", "hz", "probe.state", "-n", "6")
    assert done.returncode == 0, done.stderr
    last = done.stdout.splitlines()[-1]
    match = HZ.match(last)
    assert match, done.stdout
    rate, samples, periods, missed = (float(match.group(1)), *map(int, match.group(2, 3, 4)))
    assert samples == 6
    # 6 samples make 5 periods; a sample this reader skipped takes one period away
    assert (periods == 5) == (missed == 0) and periods + missed >= 5 and periods <= 5
    assert rate > 0


def test_bw_prints_size_times_rate(lab: Lab) -> None:
    lab.publisher()
    done = lab.ln_manager("topic", "bw", "probe.state", "-n", "4")
    assert done.returncode == 0, done.stderr
    match = re.match(r"^bandwidth: ([0-9.]+) (B|KB|MB)/s  \(940 B x ([0-9.]+) Hz\)  "
                     r"window: 4 samples, \d+ periods, \d+ missed$", done.stdout.splitlines()[-1])
    assert match, done.stdout
    scale = {"B": 1, "KB": 1e3, "MB": 1e6}[match.group(2)]
    assert float(match.group(1)) * scale == pytest.approx(940 * float(match.group(3)),
                                                          rel=1e-2, abs=1.0)


# ---- topic info --------------------------------------------------------------------------
def test_info_lists_md_layout_ring_publishers_and_subscribers(lab: Lab) -> None:
    pub = lab.publisher()
    ln.add_message_definition_dir(MDS)
    clnt = ln.client("probe_sub", lab.address)
    try:
        sub = clnt.subscribe("probe.state", "lntest/probe", buffers=4)
        done = lab.ln_manager("topic", "info", "probe.state", "--json")
        assert done.returncode == 0, done.stderr
        info = json.loads(done.stdout)
        text = lab.ln_manager("topic", "info", "probe.state")
        sub.close()
    finally:
        clnt.close()
    assert (info["name"], info["md_name"], info["message_size"]) == (
        "probe.state", "lntest/probe", 940)
    assert info["layout_hash"] == f"0x{probe_hash():016x}"
    assert info["slots"] == 5  # the queued subscriber's 4 buffers + 1
    assert info["published"] >= 1
    [publisher] = info["publishers"]
    assert (publisher["client"], publisher["pid"], publisher["buffers"]) == (
        "probe_pub", pub.pid, 1)
    assert publisher["wait_for_subscribers"] is False
    [subscriber] = info["subscribers"]
    assert (subscriber["client"], subscriber["mode"], subscriber["buffers"],
            subscriber["reader"], subscriber["transport"]) == (
        "probe_sub", "queued", 4, 0, "shm")
    assert publisher["host"] == subscriber["host"] != ""
    [ring] = info["rings"]
    assert ring["segment"] == ring["generations"][-1]
    assert info["streams"] == []
    lines = text.stdout.splitlines()
    assert text.returncode == 0
    assert lines[0] == f"topic: probe.state (id {info['id']})"
    assert lines[1] == f"md: lntest/probe (layout hash 0x{probe_hash():016x}, 940 bytes)"
    assert f"  probe_pub (pid {pub.pid}, host {publisher['host']}): port " \
        f"{publisher['port']}, 1 buffer" in lines
    assert f"  probe_sub (pid {subscriber['pid']}, host {subscriber['host']}): port " \
        f"{subscriber['port']}, queued, 4 buffers, reader 0, shm" in lines


# ---- md show -----------------------------------------------------------------------------
def test_md_show_prints_the_definition_from_the_managers_search_path(lab: Lab) -> None:
    done = lab.ln_manager("md", "show", "lntest/probe")
    assert done.returncode == 0, done.stderr
    assert done.stdout == (MDS / "lntest" / "probe").read_text()


def test_md_show_recursive_adds_the_mds_it_uses(lab: Lab) -> None:
    done = lab.ln_manager("md", "show", "lntest/adjust", "--recursive")
    assert done.returncode == 0, done.stderr
    parts = re.split(r"^# ==== (\S+): (\S+)\n", done.stdout, flags=re.M)
    assert parts[0] == ""
    names = parts[1::3]
    assert names == ["lntest/adjust", "robot/pose", "ln/string"]
    for name, path, text in zip(parts[1::3], parts[2::3], parts[3::3], strict=True):
        assert path.endswith(name)
        assert text == open(path).read()


# ---- service call ------------------------------------------------------------------------
REQUEST = {"values": [1.0, 2.0, 3.5], "offset": -2, "name": "arm",
           "target": {"position": [0.5, 1.0, 2.0], "orientation": [0.0, 0.0, 0.0, 1.0]},
           "tags": [{"data": "a"}, {"data": "b c"}]}


def test_service_call_with_yaml_like_text(lab: Lab) -> None:
    lab.provider()
    text = ('values: [1, 2, 3.5], offset: -2, name: "arm", '
            "target: {position: [0.5, 1, 2], orientation: [0, 0, 0, 1]}, tags: [a, 'b c']")
    done = lab.ln_manager("service", "call", "probe.adjust", text)
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines() == [
        "total: 4.5", 'text: "arm: a,b c"', "target:", "  position: [1.0, 2.0, 4.0]",
        "  orientation: [0.0, 0.0, 0.0, 1.0]", "count: 2"]


def test_service_call_with_json_prints_json(lab: Lab) -> None:
    lab.provider()
    done = lab.ln_manager("service", "call", "probe.adjust", json.dumps(REQUEST), "--json")
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout) == adjust(REQUEST)


def test_service_call_without_request_sends_zeros(lab: Lab) -> None:
    lab.provider()
    done = lab.ln_manager("service", "call", "probe.adjust", "--json")
    assert done.returncode == 0, done.stderr
    empty = {"values": [0.0] * 3, "offset": 0, "name": "", "tags": [],
             "target": {"position": [0.0] * 3, "orientation": [0.0] * 4}}
    assert json.loads(done.stdout) == adjust(empty)


# ---- errors ------------------------------------------------------------------------------
def test_unknown_topic_md_and_service(lab: Lab) -> None:
    for words in (["topic", "echo", "nope"], ["topic", "hz", "nope", "-n", "2"],
                  ["topic", "bw", "nope"], ["topic", "info", "nope"]):
        assert one_error(lab.ln_manager(*words), " ".join(words[:2])) == "no topic 'nope'"
    text = one_error(lab.ln_manager("md", "show", "lntest/nope"), "md show")
    assert text.startswith("message definition 'lntest/nope' not found (searched: ")
    assert str(MDS) in text
    assert one_error(lab.ln_manager("service", "call", "nope", "a: 1"), "service call") \
        == "no service 'nope'"


def test_unknown_or_bad_field_paths(lab: Lab) -> None:
    lab.publisher()
    cases = {
        "qq": "md 'lntest/probe' has no field 'qq' (its fields: count, q, target, gains, "
              "label, trace)",
        "q[7]": "index 7 out of range: 'q' has 7 elements",
        "count[0]": "'count' is not an array: [0] cannot index it",
        "target.x": "md 'robot/pose' has no field 'x' in 'target' (its fields: position, "
                    "orientation)",
        "q..x": "bad field path 'q..x' at column 2: expected NAME, .NAME or [INDEX]",
    }
    for path, error in cases.items():
        done = lab.ln_manager("topic", "echo", "probe.state", "--field", path)
        assert one_error(done, "topic echo") == f"topic 'probe.state': {error}"


def test_bad_request_text_names_the_column(lab: Lab) -> None:
    lab.provider()
    cases = {
        "values: [1, 2, 3] name: x":
            "bad request text at column 19: expected ',' or a line break between fields, "
            "found 'n'",
        "values: [1, 2": "bad request text at column 14: expected ',' or ']' in a list, "
                         "found the end",
        'name: "x': "bad request text at column 7: bad string: Unterminated string starting "
                    "at, found '\"'",
        "valuez: 1": "md 'lntest/adjust' has no field 'valuez' (its fields: values, offset, "
                     "name, target, tags)",
        "values: [1, 2]": "field 'values': expected 3 values, got 2",
        "offset: 1.5": "field 'offset': expected an integer (int32_t), not 1.5",
        "name: 12345678901234567": "field 'name': expected a string, not 12345678901234567",
    }
    for text, error in cases.items():
        assert one_error(lab.ln_manager("service", "call", "probe.adjust", text),
                         "service call") == error


def test_error_response_of_the_provider(lab: Lab) -> None:
    lab.provider()
    done = lab.ln_manager("service", "call", "probe.adjust", "name: fail")
    assert one_error(done, "service call") == \
        "service 'probe.adjust' (provider 'adjuster') answered with an error: asked to fail"


def test_layout_mismatch_of_topic_and_service(lab: Lab) -> None:
    lab.publisher("probe.other", OTHER_MDS)
    lab.provider("probe.other_adjust", OTHER_MDS)
    text = one_error(lab.ln_manager("topic", "echo", "probe.other", "-n", "1"), "topic echo")
    other = load_md("lntest/probe", [str(OTHER_MDS)])
    assert text == (f"topic 'probe.other': layout mismatch: md 'lntest/probe' found here "
                    f"({MDS / 'lntest' / 'probe'}) has hash 0x{probe_hash():016x} and 940 "
                    f"bytes, the topic has hash 0x{other.layout_hash:016x} and "
                    f"{other.struct.size} bytes")
    text = one_error(lab.ln_manager("service", "call", "probe.other_adjust", "values: [1]"),
                     "service call")
    assert text.startswith("service 'probe.other_adjust': layout mismatch: md "
                           "'lntest/adjust' found here (")
    # hz and bw need no md: they work with the topic's own layout
    done = lab.ln_manager("topic", "hz", "probe.other", "-n", "3")
    assert done.returncode == 0 and HZ.match(done.stdout.splitlines()[-1]), done.stderr


def test_usage_errors_exit_2_with_one_line(lab: Lab) -> None:
    for words, error in [
        (["topic"], "topic needs a command (one of: bw, echo, hz, info)"),
        (["topic", "nope", "x"], "unknown topic command 'nope' (one of: bw, echo, hz, info)"),
        (["topic", "echo"], "usage: topic echo NAME [-n N] [--duration S] [--field F] "
                            "[--json] [--full]"),
        (["topic", "echo", "x", "-n", "0"], "-n: '0' is not a whole number of at least 1"),
        (["topic", "hz", "x", "--window", "1"],
         "--window: '1' is not a whole number of at least 2"),
        (["topic", "echo", "x", "--bogus"], "unknown option '--bogus'"),
    ]:
        done = lab.ln_manager(*words)
        assert done.returncode == 2, (words, done.stderr)
        assert done.stderr.splitlines()[-1].endswith(f": error: {error}"), done.stderr
        assert len(done.stderr.splitlines()) == 1


def test_no_manager_is_one_line(lab: Lab) -> None:
    done = lab.ln_manager("topic", "info", "x", "--manager", "127.0.0.1:1")
    text = one_error(done, "topic info")
    assert text.startswith("cannot reach the manager at 127.0.0.1:1: ")


def test_ctrl_c_ends_a_following_echo_and_its_subscriber(lab: Lab) -> None:
    lab.publisher()
    echo = subprocess.Popen([sys.executable, "-m", "links_and_nodes.manager", "topic", "echo",
                             "probe.state", "--field", "count"], stdout=subprocess.PIPE,
                            text=True, env=lab.client_env(), preexec_fn=sigint_default)
    lab.procs.append(echo)
    assert echo.stdout is not None
    assert echo.stdout.readline().strip().isdigit()
    info = json.loads(lab.ln_manager("topic", "info", "probe.state", "--json").stdout)
    assert [(s["client"], s["mode"], s["transport"]) for s in info["subscribers"]] == [
        ("ln_topic_echo", "latest", "shm")]
    echo.send_signal(signal.SIGINT)
    assert echo.wait(60) == 0
    wait_for(lambda: json.loads(lab.ln_manager("topic", "info", "probe.state", "--json")
                                .stdout)["subscribers"] == [], "the echo's subscriber gone")
