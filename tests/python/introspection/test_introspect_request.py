"""The request text of `service call` (YAML-like flow style or JSON) and its check against
the request section of an md, and the words of the introspection commands: values parsed,
every error one line naming the column or the field."""

from __future__ import annotations

import math
from typing import Any

import pytest

from links_and_nodes.manager.frontends.commands import phrases
from links_and_nodes.tools.commands import ArgError
from links_and_nodes.tools.commands import parse_words as table_words
from links_and_nodes.tools.introspection.client import load_md
from links_and_nodes.tools.introspection.request import RequestTextError, conform, parse

from .conftest import MDS


@pytest.mark.parametrize(("text", "values"), [
    ("", {}),
    ("  {}  ", {}),
    ("a: 1, b: [1, 2], name: \"x\"", {"a": 1, "b": [1, 2], "name": "x"}),
    ('{"a": 1.5, "b": [true, false, null], "c": {"d": "e"}}',
     {"a": 1.5, "b": [True, False, None], "c": {"d": "e"}}),
    ("a: 1\nb: -2.5e3\n# a comment\nc: hello world", {"a": 1, "b": -2500.0,
                                                      "c": "hello world"}),
    ("p: {x: 0x10, y: +3}, s: 'it''s', t: [ ]", {"p": {"x": 16, "y": 3}, "s": "it's",
                                                  "t": []}),
    ("tags: [a, 'b c', \"d\\u00e9\"], n: [\n  1,\n  2\n]", {"tags": ["a", "b c", "dé"],
                                                          "n": [1, 2]}),
    ("x: inf, y: -inf", {"x": math.inf, "y": -math.inf}),
])
def test_parse(text: str, values: dict[str, object]) -> None:
    assert parse(text) == values


@pytest.mark.parametrize(("text", "error"), [
    ("a 1", "bad request text at column 3: expected ':' after 'a', found '1'"),
    ("a: 1 b: 2", "bad request text at column 6: expected ',' or a line break between "
                  "fields, found 'b'"),
    ("a: [1, 2", "bad request text at column 9: expected ',' or ']' in a list, found the end"),
    ("a: {b: 1", "bad request text at column 9: expected ',' or a line break between fields "
                 "or '}', found the end"),
    ("a: ", "bad request text at column 4: expected a value, found the end"),
    ("a: 1, a: 2", "bad request text at column 7: field 'a' given twice, found 'a'"),
    ("a: 'x", "bad request text at column 4: string not closed, found \"'\""),
    ("{a: 1} x", "bad request text at column 8: expected ',' or the end of the request, "
                 "found 'x'"),
    (": 1", "bad request text at column 1: expected a field name, found ':'"),
    ("a: 1\nb 2", "bad request text at line 2, column 3: expected ':' after 'b', found '2'"),
])
def test_parse_errors_name_the_column(text: str, error: str) -> None:
    with pytest.raises(RequestTextError) as info:
        parse(text)
    assert str(info.value) == error


def request_layout():  # type: ignore[no-untyped-def]
    return load_md("lntest/adjust", [str(MDS)]).sections["request"]


def test_conform_takes_tuples_and_numpy_values() -> None:
    import numpy as np

    values = conform(request_layout(), {"values": np.array([1.0, 2.0, 3.0]),
                                        "offset": np.int16(-4), "target": {"position": (1, 2, 3)}})
    assert values == {"values": [1.0, 2.0, 3.0], "offset": -4,
                      "target": {"position": [1.0, 2.0, 3.0]}}
    assert type(values["offset"]) is int


def test_conform_checks_types_and_wraps_one_field_messages() -> None:
    values = conform(request_layout(), parse(
        "values: [1, 2, 3.5], offset: -2.0, name: arm, target: {position: [1, 2, 3]}, "
        "tags: [a, {data: b}]"))
    assert values == {"values": [1.0, 2.0, 3.5], "offset": -2, "name": "arm",
                      "target": {"position": [1.0, 2.0, 3.0]},
                      "tags": [{"data": "a"}, {"data": "b"}]}
    assert isinstance(values["values"][0], float) and isinstance(values["offset"], int)


@pytest.mark.parametrize(("text", "error"), [
    ("nope: 1", "md 'lntest/adjust' has no field 'nope' (its fields: values, offset, name, "
                "target, tags)"),
    ("values: 1", "field 'values': expected a list, not 1"),
    ("values: [1, 2, 3, 4]", "field 'values': expected 3 values, got 4"),
    ("values: [1, x, 3]", "field 'values[1]': expected a number, not the string 'x'"),
    ("offset: 4294967296", "field 'offset': 4294967296 is out of range for int32_t "
                           "(-2147483648..2147483647)"),
    ("name: 'seventeen bytes!!'", "field 'name': 17 bytes do not fit in char[16]"),
    ("target: {position: [1, 2, 3], bogus: 1}",
     "target: md 'robot/pose' has no field 'bogus' (its fields: position, orientation)"),
    ("target: 5", "field 'target': expected a mapping of the fields of 'robot/pose' "
                  "(position, orientation), not 5"),
    ("tags: [[1]]", "field 'tags[0].data': expected a string, not a list"),
    ("tags: a", "field 'tags': expected a list, not the string 'a'"),
])
def test_conform_errors_name_the_field(text: str, error: str) -> None:
    with pytest.raises(RequestTextError) as info:
        conform(request_layout(), parse(text))
    assert str(info.value) == error


def parse_words(words: list[str]) -> tuple[str, dict[str, Any]]:
    """The command of the table `ln_manager WORDS` names and its checked arguments."""
    cmd, rest = phrases.match(words, "cli")
    return cmd.name, table_words(cmd, rest, "cli")


def test_command_words() -> None:
    key, args = parse_words(["topic", "echo", "x", "-n", "3", "--field=q[1]", "--json"])
    assert key == "topic_echo"
    assert (args["name"], args["n"], args["field"], args["json"], args["full"]) == (
        "x", 3, "q[1]", True, False)
    key, args = parse_words(["service", "call", "s", "a:", "-1,", "b:", "2", "--timeout", "2"])
    assert (args["request"], args["timeout"]) == ("a: -1, b: 2", 2.0)
    key, args = parse_words(["service", "call", "s"])
    assert args["request"] is None
    key, args = parse_words(["md", "show", "-r", "robot/pose"])
    assert (args["name"], args["recursive"]) == ("robot/pose", True)
    _, args = parse_words(["topic", "hz", "t", "--duration", "1.5", "--window", "50"])
    assert (args["duration"], args["window"], args["n"]) == (1.5, 50, None)


@pytest.mark.parametrize(("words", "error"), [
    (["md"], "md needs a command (one of: show)"),
    (["topic", "echo", "a", "b"], "usage: topic echo NAME [-n N] [--duration S] [--field F] "
                                  "[--json] [--full]"),
    (["topic", "hz", "t", "--duration", "nan"], "--duration: 'nan' is not a number of "
                                                "seconds above 0"),
    (["topic", "hz", "t", "--duration", "x"], "--duration: 'x' is not a number of seconds "
                                              "above 0"),
    (["topic", "echo", "t", "--field"], "--field needs a value"),
    (["topic", "echo", "t", "--json=1"], "--json takes no value"),
])
def test_bad_command_words(words: list[str], error: str) -> None:
    with pytest.raises(ArgError) as info:
        parse_words(words)
    assert str(info.value) == error
