"""The md grammar (editors/tree-sitter-lnmd) against ln_generate's own parser on random
lines: a file ln_generate reads without error parses without ERROR or MISSING node, and a
file with a syntax error in ln_generate's eyes has an error node. Where ln_generate only
objects to structure or values (a section keyword in a plain message, a size of 0, a
repeated define), the grammar may accept or refuse: that is left to the language server."""

from __future__ import annotations

from collections.abc import Callable

from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from ln_generate.parser import parse

from .ts_grammars import Grammar

TOKENS = (
    "double uint8_t int char pose x y_1 define as service event request response connect call "
    '* [ ] ( ) + - / 3 0x1f 0 08 "robot/pose" "a #note @ 1x'
).split()
#: contexts a line goes into: after a plain field, inside a service's request section
CONTEXTS = ["double first\n", "service\nrequest\n"]
#: what ln_generate reports about structure or values, not syntax
NOT_SYNTAX = (
    "array size must be positive",
    "division by zero",
    "is not a whole number",
    "must come before any section",
    "outside a",
    "unknown section keyword",
    "duplicate define",
    "empty message definition",
    "' section",  # a service or event without one of its sections
)

tokens = st.lists(
    st.tuples(st.sampled_from(TOKENS), st.sampled_from(["", " ", "\t"])), min_size=1, max_size=6
).map(lambda ts: "".join(t + sep for t, sep in ts))
numbers = st.sampled_from(["0", "1", "3", "08", "0x1f", "0X2", "12"])
sizes = st.recursive(
    numbers,
    lambda inner: st.one_of(
        st.tuples(inner, st.sampled_from(["+", "-", "*", "/", " * ", " - "]), inner).map("".join),
        inner.map(lambda e: f"({e})"),
        inner.map(lambda e: f"-{e}"),
    ),
    max_leaves=5,
)
fields = st.builds(
    lambda type_, star, name, size, comment: f"{type_}{star}{name}{size}{comment}",
    st.sampled_from(["double", "uint8_t", "int", "pose", "event", "request", "define"]),
    st.sampled_from([" ", "* ", " *", " * ", "*"]),
    st.sampled_from(["x", "call", "as", "double", "y_1"]),
    st.one_of(st.just(""), sizes.map(lambda s: f"[{s}]"), sizes.map(lambda s: f" [ {s} ]")),
    st.sampled_from(["", " # note", "#"]),
)
defines = st.builds(
    lambda name, target: f"define {name} as {target}",
    st.sampled_from(["pose", "event", "x"]),
    st.sampled_from(['"robot/pose"', '"a/b"', '""', "pose", '"a" x']),
)
lines = st.one_of(tokens, fields, defines)


@settings(max_examples=400, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(context=st.sampled_from(CONTEXTS), line=lines)
def test_grammar_agrees_with_ln_generate(
    grammar: Callable[[str], Grammar], context: str, line: str
) -> None:
    source = (context + line + "\n").encode()
    errors = [d.message for d in parse(source, "t.md").errors]
    syntax = [m for m in errors if not any(phrase in m for phrase in NOT_SYNTAX)]
    root = grammar("lnmd").parse(source).root_node
    if not errors:
        event("ln_generate accepts")
        assert not root.has_error, f"{source!r}: ln_generate accepts it, the grammar gives {root}"
    elif syntax:
        event("ln_generate: syntax error")
        assert root.has_error, f"{source!r}: ln_generate says {syntax}, the grammar accepts it"
    else:
        event("ln_generate: structure or value error only")
