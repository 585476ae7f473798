"""The seam between ln_zenoh and its native core beyond the C signatures: the core's counters
are stats.TopicStats's in their order, the libln function table is built from the core's own
list, a core that disagrees (or predates these checks) is refused with one clear reason, and
the error codes the Python side tells apart come from libln's table."""

from __future__ import annotations

import ctypes
from dataclasses import fields
from typing import Any

import pytest
from zenoh_sites import require_native_core

from links_and_nodes import _clientlib, _libln
from links_and_nodes.zenoh_bridge import native
from links_and_nodes.zenoh_bridge.stats import TopicStats


class _Names:
    """A stand-in for a core function returning static names."""

    def __init__(self, text: str) -> None:
        self.text = text

    def __call__(self) -> bytes:
        return self.text.encode()


class _FakeCore:
    def __init__(self, **functions: str) -> None:
        for name, text in functions.items():
            setattr(self, name, _Names(text))


def test_the_built_core_agrees() -> None:
    require_native_core()
    core = native.load_core()
    native.check_seam(core)
    assert native._names(core, "lnz_counter_names") == list(native.COUNTER_FIELDS)
    names = native._names(core, "lnz_libln_functions")
    table = native.ln_fns(core, _libln.lib)
    assert [name for name, _ in table._fields_] == names
    assert "read_borrow" in names and "write" in names
    for name in names:
        assert getattr(table, name) == ctypes.cast(getattr(_libln.lib, f"ln_{name}"),
                                                   ctypes.c_void_p).value


def test_counters_are_topic_stats_numbers_in_order() -> None:
    numbers = [f.name for f in fields(TopicStats) if f.name not in ("direction", "md_name",
                                                                     "state")]
    assert list(native.COUNTER_FIELDS) == numbers
    assert [name for name, _ in native.Counters._fields_] == numbers


def test_a_core_with_other_counters_is_refused() -> None:
    swapped = list(native.COUNTER_FIELDS)
    swapped[0], swapped[1] = swapped[1], swapped[0]
    core: Any = _FakeCore(lnz_counter_names=" ".join(swapped) + " ",
                          lnz_libln_functions="write ")
    with pytest.raises(native.CoreUnavailable, match="its counters differ from this bridge's"
                       r".*core sent read .*rebuild the core"):
        native.check_seam(core)


def test_a_core_from_older_sources_is_refused() -> None:
    with pytest.raises(native.CoreUnavailable, match="no lnz_counter_names: built from older"):
        native.check_seam(_FakeCore())


def test_a_core_asking_for_what_libln_lacks_is_refused() -> None:
    core: Any = _FakeCore(lnz_libln_functions="write no_such_function ")
    with pytest.raises(native.CoreError, match="ln_no_such_function"):
        native.ln_fns(core, _libln.lib)


def test_error_codes_come_from_the_table() -> None:
    by_name = {cls.name: code for code, cls in _libln.ERRORS_BY_CODE.items()}
    for name in ("EAGAIN", "ETIMEOUT", "EOVERRUN", "EINTR"):
        assert getattr(_clientlib, f"LN_{name}") == by_name[name]
