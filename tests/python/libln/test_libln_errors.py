"""The Python exception classes are exactly libln's error table: one LnError subclass per
entry, named by the documented rule, carrying the code, name and message of the C side.
Needs the built libln; skipped without it only outside CI (CI unset), where it must fail."""

import ctypes
import os
import pickle

import pytest

import links_and_nodes as ln
from links_and_nodes.errors import class_name

try:
    from links_and_nodes import _libln
except ln.LibraryNotFoundError as exc:
    if os.environ.get("CI"):
        raise
    pytest.skip(f"libln is not built: {exc}", allow_module_level=True)

lib = _libln.lib


def c_table() -> list[tuple[int, str, str]]:
    """The table straight from C, read with our own declarations rather than _libln's."""
    name = ctypes.CFUNCTYPE(ctypes.c_char_p, ctypes.c_int)(("ln_error_name", lib))
    text = ctypes.CFUNCTYPE(ctypes.c_char_p, ctypes.c_int)(("ln_strerror", lib))
    table = []
    code = -1
    while (raw := name(code)) is not None:
        table.append((code, raw.decode(), text(code).decode()))
        code -= 1
    return table


def test_one_class_per_entry() -> None:
    table = c_table()
    assert len(table) == lib.ln_error_count() >= 21
    assert sorted(_libln.ERRORS_BY_CODE) == sorted(code for code, _, _ in table)
    for code, name, text in table:
        cls = _libln.ERRORS_BY_CODE[code]
        assert issubclass(cls, ln.LnError)
        assert (cls.code, cls.name, cls.text) == (code, name, text)
        assert cls.__name__ == class_name(name)
        assert getattr(ln, cls.__name__) is cls


def test_names_follow_the_documented_rule() -> None:
    assert class_name("ETIMEOUT") == "LnTimeoutError"
    assert ln.LnTimeoutError.code == -3
    assert ln.LnBadhandleError.name == "EBADHANDLE"
    names = [cls.__name__ for cls in _libln.ERRORS_BY_CODE.values()]
    assert len(set(names)) == len(names)


def test_error_from_code() -> None:
    error = _libln.error_from_code(-3, "waiting for the manager")
    assert isinstance(error, ln.LnTimeoutError)
    assert str(error) == "ETIMEOUT: timed out: waiting for the manager"
    unknown = _libln.error_from_code(-12345)
    assert type(unknown) is ln.LnError and unknown.code == -12345


def test_errcheck_raises_the_generated_class() -> None:
    major, minor = (int(n) for n in ln.__version__.split(".")[:2])
    assert _libln.ln_version_check(major, minor) == 0
    with pytest.raises(ln.LnVersionError):
        _libln.ln_version_check(major + 1, 0)
    with pytest.raises(ln.LnInvalError):
        _libln.ln_version_check(-1, 0)


def test_library_version_matches_package() -> None:
    assert _libln.ln_version().decode() == ln.__version__


def test_classes_pickle_by_name() -> None:
    error = pickle.loads(pickle.dumps(ln.LnBusyError("ring 3")))
    assert type(error) is ln.LnBusyError and error.detail == "ring 3"
    assert str(error) == "EBUSY: resource busy: ring 3"


def test_unknown_attribute() -> None:
    with pytest.raises(AttributeError):
        ln.LnNoSuchThingError  # noqa: B018
