"""Robustness: whatever bytes a configuration holds, the reader either returns a model or
raises ConfigError; it never fails with another exception.  Random bytes, and random
lines built from the language's own words (which get much deeper into the reader)."""

from __future__ import annotations

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from links_and_nodes.manager.config import Config, ConfigError, parse_text

# A file name in a directory that does not exist: includes find nothing.
FILE = "/nonexistent-lnc-fuzz-dir/fuzz.lnc"

WORDS = [
    "instance", "name:", "manager:", ":54414", "process", "state", "group", "template",
    "process_template", "network", "defines", "hosts", "node_map", "t(a, b=\"x\")",
    "use_template:", "t(1)", "t", "a:", "b", "p", "%(", ")", "(", "%(a)", "%(env X, y)",
    "%(subst \"a\", \"b\", \"c\")", "%(dirname a/b)", "%(get_port_from_string x)",
    "%(CURDIR)", "%(_PROCESS)", "%(instance_name)", "%(manager)", "%(%(a))", "[", "]", "\"",
    "#", ",", "!", "*", "add", "flags:", "members:", "depends_on:", "start_before:",
    "start_on_ready:", "command:", "policy:", "FIFO", "priority:", "5", "-1", "ifdef",
    "ifndef", "include", "include_glob", "optional_include", "push_name_prefix:",
    "pop_name_prefix", "requires_version", "0.1", "environment:", "A=1", "affinity:", "0-3",
    "set_resource_limits:", "core:1:2", "watchdog_topic:", "x, 5", "ready_regex:",
    "term_signal:", "INT", "eth0:1.2.3.4", "daemon_port:5", "allow_empty", "output_logfile:",
    "add_message_definition_dir:", "max_output_lines:", "restart:", "always", "ready_time:",
    "1ms", "check:", "\\", "a/b", "\t", "    ", "\r", "\ufeff", "\x00", "é",
    "topics", "member_interfaces:", "preferred_gateways:", "a/eth0", "!a/eth0", "10.0.0.0/8",
    "fd00::/64", "a:", "eth0:10.0.0.1,", "transport:tcp", "transport:", "robot.*:", "data_port:5",
    # the original's conditional functions and old syntax (no shell: nothing may run here)
    '%(ifdef "a", "b", "c")', '%(ifndef "a", "%(b)")', '%(ifeq "%(a)", "x", "y", "%(z)")',
    '%(ifexists "/", "y")', '"%(ifdef "a", "%(ifeq "1", "1", "x")")"', "%(basename a/b)",
    "undef:", "undef: a", "append environment", "append environment X:", "stack_size:", "8M",
    "%(ifeq", '"a",',
]

lines = st.lists(st.sampled_from(WORDS), max_size=8).map(" ".join)
texts = st.lists(lines, max_size=30).map("\n".join)


def parse(data: bytes | str) -> None:
    try:
        config = parse_text(data, FILE, env={})
    except ConfigError as err:
        assert err.problems and str(err)
    else:
        assert isinstance(config, Config)


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.binary(max_size=400))
def test_random_bytes(data: bytes) -> None:
    parse(data)


@settings(max_examples=600, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(texts)
def test_random_word_soup(text: str) -> None:
    parse(text)


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.text(alphabet=st.sampled_from('%()"[]#:,\\ \nab'), max_size=200))
def test_random_punctuation(text: str) -> None:
    parse("instance\nname: n\nmanager: :1\nprocess p\ncommand: " + text)
