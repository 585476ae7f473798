"""The wire schema parser (wire/schema.py) reports each kind of mistake as file:line:col with
a sentence, and reads daemon.schema into the model the generators use."""

from __future__ import annotations

import pytest

from links_and_nodes.wire import gen_cpp, schema

HEAD = "protocol t\nenum Msg u8 message_types {\n    A = 1\n}\nmessage A {\n}\n"


@pytest.mark.parametrize(("text", "where", "what"), [
    ("enum Msg u8 {\n A = 1\n}\n", "1:1", "starts with 'protocol NAME'"),
    (HEAD + "record R {\n    x u7\n}\n", "8:7", "unknown type u7"),
    (HEAD + "record R {\n    x str(NOPE)\n}\n", "8:11", "NOPE is not an integer constant"),
    (HEAD + "const K = 1\nconst K = 2\n", "8:1", "K is declared twice (first at line 7)"),
    (HEAD + "enum E u8 {\n    X = 256\n}\n", "8:9", "256 does not fit u8"),
    (HEAD + "flags F u8 {\n    a = 3\n}\n", "8:9", "a flag must be a single bit"),
    (HEAD + "message B {\n}\n", "7:9", "message B is not an entry of Msg"),
    ("protocol t\nenum Msg u8 message_types {\n    A = 1\n    B = 2\n}\nmessage A {\n}\n",
     "4:5", "entry B has no message layout"),
    (HEAD + "record R {\n    x u8\n    x u16\n}\n", "9:5", "field x is declared twice"),
    (HEAD + "record R {\n    x u8 = 300\n}\n", "8:12", "default 300 does not fit u8"),
    (HEAD + "record R {\n    x list<R>\n}\n", "8:12", "unknown type R"),
    (HEAD + "record R {\n    x u8\n", "9:1", "expected a field name or '}', got end of file"),
    (HEAD + "record R {\n    x $\n}\n", "8:7", "unexpected character '$'"),
])
def test_errors_name_file_line_and_column(text: str, where: str, what: str) -> None:
    with pytest.raises(schema.SchemaError) as info:
        schema.parse(text, "x.schema")
    assert str(info.value).startswith(f"x.schema:{where}: "), str(info.value)
    assert what in str(info.value)


def test_daemon_schema_model() -> None:
    s = schema.load(schema.DAEMON_SCHEMA)
    assert s.protocol == "daemon"
    assert s.message_enum.value("SPAWN") == 0x10
    assert s.enums["Err"].value("PULL_FAILED") == s.enums["Err"].value("LOGGER_FAILED") == 16
    spawn = s.messages["SPAWN"]
    assert spawn.type_name == "Spawn"
    options = next(f for f in spawn.fields if f.name == "options")
    assert options.type.kind == "flags" and options.default == ["use_pty"]
    rlimits = next(f for f in spawn.fields if f.name == "rlimits")
    assert rlimits.type.item is not None and s.min_size(rlimits.type.item) == 4 + 8 + 8
    name = spawn.fields[0]
    assert (name.type.kind, name.type.limit, name.type.explicit) == ("str", 255, True)
    assert next(f for f in spawn.fields if f.name == "cwd").type.limit == 4 << 20
    assert "last field" in str(pytest.raises(schema.SchemaError, schema.parse, HEAD.replace(
        "message A {\n}", "message A {\n    t tail\n    x u8\n}"), "y").value)


def test_cpp_header_has_every_message() -> None:
    s = schema.load(schema.DAEMON_SCHEMA)
    header = gen_cpp.generate(s)
    for m in s.messages.values():
        assert f"struct {m.type_name} {{" in header
        assert f"inline bool decode(proto::Reader &r, {m.type_name} &" in header
    assert "constexpr size_t kMaxName = 255;" in header
    assert "spawn = 0x10," in header
