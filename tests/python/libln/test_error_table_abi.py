"""The released error codes are ABI: each code keeps its name and its Python class forever.

This table is written out by hand on purpose (not read from libln), so a renumbered,
renamed or removed entry fails here even though the C table and the bindings agree.
New entries may be appended below the last one."""

from __future__ import annotations

import pytest

import links_and_nodes as ln

RELEASED = [
    (-1, "EINVAL", "LnInvalError"),
    (-2, "ENOMEM", "LnNomemError"),
    (-3, "ETIMEOUT", "LnTimeoutError"),
    (-4, "EAGAIN", "LnAgainError"),
    (-5, "ECONNECTION", "LnConnectionError"),
    (-6, "EPROTOCOL", "LnProtocolError"),
    (-7, "EVERSION", "LnVersionError"),
    (-8, "ELAYOUT", "LnLayoutError"),
    (-9, "ENOTFOUND", "LnNotfoundError"),
    (-10, "EEXIST", "LnExistError"),
    (-11, "ELIMIT", "LnLimitError"),
    (-12, "ETOOBIG", "LnToobigError"),
    (-13, "ECLOSED", "LnClosedError"),
    (-14, "EBUSY", "LnBusyError"),
    (-15, "EOVERRUN", "LnOverrunError"),
    (-16, "ESYS", "LnSysError"),
    (-17, "EPERM", "LnPermError"),
    (-18, "EMD", "LnMdError"),
    (-19, "ESERVICE", "LnServiceError"),
    (-20, "EBADHANDLE", "LnBadhandleError"),
    (-21, "EINTR", "LnIntrError"),
]


@pytest.mark.parametrize(("code", "name", "class_name"), RELEASED)
def test_released_code_keeps_its_name_and_class(code: int, name: str, class_name: str) -> None:
    from links_and_nodes import _libln

    assert _libln.ln_error_name(code).decode() == name
    cls = getattr(ln, class_name)
    assert issubclass(cls, ln.LnError) and cls.code == code and cls.name == name
