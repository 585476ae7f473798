"""ln_zenoh's choice of data path and the Python side of its native core: `--native on` without
the core is one clear error, `auto` says it goes on through Python; the core's counters add
up with the topic's own in the statistics; socket directories of killed bridges are removed.
(The sites tests run every bridge scenario through both data paths: conftest.py.)"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
from zenoh_sites import ROOT, require_zenoh

from links_and_nodes.zenoh_bridge import native
from links_and_nodes.zenoh_bridge.stats import Stats


def _bridge(*args: str, core: str) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "PYTHONPATH": str(ROOT / "python"), native.ENV: core}
    return subprocess.run([sys.executable, "-m", "links_and_nodes.zenoh_bridge.cli",
                           "--manager", "127.0.0.1:9", "--out", "x", *args],
                          env=env, capture_output=True, text=True, timeout=60)


def test_native_on_without_the_core_is_an_error(tmp_path: Path) -> None:
    require_zenoh()
    missing = tmp_path / "nowhere" / native.SONAME
    got = _bridge("--native", "on", core=str(missing))
    assert got.returncode == 1, got.stderr
    assert "native on, but the native core cannot be loaded" in got.stderr
    assert str(missing) in got.stderr


def test_native_auto_without_the_core_goes_on_through_python(tmp_path: Path) -> None:
    require_zenoh()
    got = _bridge(core=str(tmp_path / native.SONAME))
    assert "the native core is not built: topic samples go through Python" in got.stderr
    # it went on: to the manager, which is not there
    assert got.returncode == 1 and "127.0.0.1:9" in got.stderr, got.stderr


def test_native_auto_with_a_foreign_library_says_it_does_not_match() -> None:
    """A library that loads but is no core of these sources (here: libln itself) is named
    with the reason, not reported as missing."""
    require_zenoh()
    from links_and_nodes import _libln

    foreign = str(native._native.file_of(_libln.lib, "ln_version"))
    got = _bridge(core=foreign)
    assert "the native core does not match this bridge" in got.stderr, got.stderr
    assert "lnz_counter_names" in got.stderr and foreign in got.stderr
    assert got.returncode == 1 and "127.0.0.1:9" in got.stderr, got.stderr


def test_bad_native_setting_is_a_usage_error() -> None:
    require_zenoh()
    got = _bridge("--native", "maybe", core="")
    assert got.returncode == 2 and "--native" in got.stderr


def test_core_counters_add_to_the_topics_own() -> None:
    stats = Stats()
    topic = stats.topic("arm.state", "in")
    topic.received, topic.published, topic.superseded, topic.last_seq = 3, 2, 1, 7
    core = native.Counters(received=10, published=9, gaps=4, last_seq=0)
    stats.add_native("arm.state", "in", core)
    got = stats.as_dict()["topics"]["in:arm.state"]
    assert (got["received"], got["published"], got["superseded"], got["gaps"],
            got["last_seq"]) == (13, 11, 1, 4, 7)
    core.last_seq, core.published = 20, 15  # the core counts on
    got = stats.as_dict()["topics"]["in:arm.state"]
    assert (got["published"], got["last_seq"]) == (17, 20)
    assert [name for name, _ in native.Counters._fields_] == list(native.COUNTER_FIELDS)
    assert set(native.COUNTER_FIELDS) <= set(got)


def test_socket_directories_of_dead_bridges_are_removed(tmp_path: Path,
                                                       monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr("tempfile.tempdir", str(tmp_path))
    gone = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True)
    dead = tmp_path / f"{native.DIR_PREFIX}{gone.stdout.strip()}.abc"
    alive = tmp_path / f"{native.DIR_PREFIX}{os.getpid()}.def"
    other = tmp_path / f"{native.DIR_PREFIX}notapid.ghi"
    for path in (dead, alive, other):
        path.mkdir()
        (path / "session.sock").write_text("")
    native.remove_stale_dirs()
    assert not dead.exists() and alive.exists() and other.exists()
