"""libln's internal API (libln/src/ln_admin.h) reaches Python only through libln_admin.so,
which _adminlib loads from links_and_nodes/ next to the libln.so.1 the bindings use; libln.so
itself does not offer it.  Needs the built libraries; skipped without them only outside CI."""

import ctypes
import os

import pytest

import links_and_nodes as ln

try:
    from links_and_nodes import _adminlib, _libln, _native
except ln.LibraryNotFoundError as exc:
    if os.environ.get("CI"):
        raise
    pytest.skip(f"libln or libln_admin.so is not built: {exc}", allow_module_level=True)


def test_the_admin_library_lies_next_to_the_client_library() -> None:
    libln = _native.file_of(_libln.lib, "ln_version")
    admin = _native.file_of(_adminlib.lib, "ln_ring_admin_create")
    assert admin == libln.parent / "links_and_nodes" / "libln_admin.so"


def test_the_client_library_does_not_offer_the_internal_api() -> None:
    for name in ("ln_ring_admin_create", "ln_ring_tap_open", "ln_ring_segment_size",
                 "ln_host_id"):
        with pytest.raises(AttributeError):
            getattr(_libln.lib, name)
        assert getattr(_adminlib.lib, name) is not None


def test_admin_errors_carry_the_admin_librarys_last_error() -> None:
    handle = _adminlib.RingAdminHandle()
    name = f"/ln.admin-test-{os.getpid()}.1.1"
    with pytest.raises(ln.LnNotfoundError) as raised:
        _adminlib.ln_ring_admin_open(ctypes.byref(handle), name.encode())
    assert name in _adminlib.last_error()
    assert name in str(raised.value)


def test_host_id_is_one_line() -> None:
    host = _adminlib.host_id()
    assert host and "\n" not in host
    if "LN_HOST_ID" not in os.environ:
        assert "/" in host  # hostname/boot_id
