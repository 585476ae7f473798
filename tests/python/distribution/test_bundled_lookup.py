"""Where the package looks for its native parts when a wheel carries them (bundled.py): an
explicit LN_LIBRARY_PATH / LN_DAEMON still wins, then the package's lib/ and bin/, and only
then the checkout's build and the system; `python -m links_and_nodes.bundled` prints the
flags for that layout and refuses a package without native parts (a checkout)."""

from pathlib import Path

import pytest

from links_and_nodes import _native, bundled
from links_and_nodes.manager.processes import daemon_launch


@pytest.fixture
def wheel_layout(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A package root laid out as an installed wheel's: lib/libln.so.1, bin/ln_daemon,
    include/ln/ln.h (empty files: only their places matter here)."""
    for name in ("lib/libln.so.1", "bin/ln_daemon", "include/ln/ln.h"):
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / name).write_text("")
    for attr, sub in (("ROOT", ""), ("LIB", "lib"), ("BIN", "bin"), ("INCLUDE", "include")):
        monkeypatch.setattr(bundled, attr, tmp_path / sub if sub else tmp_path)
    monkeypatch.delenv("LN_LIBRARY_PATH", raising=False)
    monkeypatch.delenv("LN_DAEMON", raising=False)
    return tmp_path


def test_the_package_copy_comes_first_and_alone(wheel_layout: Path) -> None:
    found = list(_native.candidates("libln.so.1", "LN_LIBRARY_PATH", "libln"))
    assert found == [str(wheel_layout / "lib" / "libln.so.1")]
    assert daemon_launch.daemon_executable() == str(wheel_layout / "bin" / "ln_daemon")


def test_an_explicit_path_still_wins(wheel_layout: Path,
                                     monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("LN_LIBRARY_PATH", "/opt/ln/lib/libln.so.1")
    monkeypatch.setenv("LN_DAEMON", "/opt/ln/bin/ln_daemon")
    assert list(_native.candidates("libln.so.1", "LN_LIBRARY_PATH", "libln")) == [
        "/opt/ln/lib/libln.so.1"]
    assert daemon_launch.daemon_executable() == "/opt/ln/bin/ln_daemon"


def test_what_the_package_does_not_carry_is_looked_up_as_before(wheel_layout: Path) -> None:
    found = list(_native.candidates("libln_zenoh_core.so", "LN_ZENOH_CORE", "ln_zenoh_core"))
    assert str(wheel_layout / "lib" / "libln_zenoh_core.so") not in found
    assert found[-1] == "libln_zenoh_core.so"  # the system loader, last


def test_flags(wheel_layout: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert bundled.main(["--cflags", "--libs"]) == 0
    lib = wheel_layout / "lib"
    assert capsys.readouterr().out.split() == [
        f"-I{wheel_layout / 'include'}", f"-L{lib}", "-l:libln.so.1", f"-Wl,-rpath,{lib}"]
    assert bundled.main(["--libs", "--pull"]) == 0
    assert "-l:libln_pull.so.1" in capsys.readouterr().out.split()


def test_a_checkout_carries_no_native_parts(capsys: pytest.CaptureFixture[str]) -> None:
    assert bundled.shared_object("libln.so.1") is None and bundled.program("ln_daemon") is None
    assert bundled.main(["--cflags"]) == 1
    assert "carries no native parts" in capsys.readouterr().err
