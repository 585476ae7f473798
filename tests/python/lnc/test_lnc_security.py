"""The security keys of the instance section (docs/security.md): `security`,
`client_key_file`, `client_uids`, `client_gids`, `webui_tls_cert`, `webui_tls_key` — their
values, the defaults, paths relative to the file, and errors at file:line:col."""

from __future__ import annotations

from pathlib import Path

import pytest

from links_and_nodes.manager.config import ConfigError, load


def _lnc(tmp_path: Path, extra: str) -> Path:
    path = tmp_path / "x.lnc"
    path.write_text(f"instance\nname: sec_test\nmanager: :12345\n{extra}\n")
    return path


def test_defaults_are_unset(tmp_path: Path) -> None:
    inst = load(_lnc(tmp_path, "")).instance
    assert (inst.security, inst.client_key_file, inst.client_uids, inst.client_gids,
            inst.webui_tls_cert, inst.webui_tls_key) == (None,) * 6


@pytest.mark.parametrize("level", ["none", "authenticate", "encrypt"])
def test_security_levels(tmp_path: Path, level: str) -> None:
    assert load(_lnc(tmp_path, f"security: {level}")).instance.security == level


def test_paths_and_id_lists(tmp_path: Path) -> None:
    inst = load(_lnc(tmp_path, "client_key_file: keys/client.key\n"
                               "client_uids: 0, robot 1001\nclient_gids: dialout\n"
                               "webui_tls_cert: tls/cert.pem\nwebui_tls_key: tls/key.pem")).instance
    assert inst.client_key_file == str(tmp_path / "keys" / "client.key")
    assert inst.client_uids == ["0", "robot", "1001"]
    assert inst.client_gids == ["dialout"]
    assert (inst.webui_tls_cert, inst.webui_tls_key) == \
        (str(tmp_path / "tls" / "cert.pem"), str(tmp_path / "tls" / "key.pem"))


@pytest.mark.parametrize(("line", "error"), [
    ("security: paranoid",
     r"x\.lnc:4:11: security must be none, authenticate or encrypt, not 'paranoid'"),
    ("client_uids: ,", r"x\.lnc:4:14: client_uids needs at least one user or group"),
    ("securty: none", r"x\.lnc:4:1: .*securty.*security"),
])
def test_errors_name_the_place(tmp_path: Path, line: str, error: str) -> None:
    with pytest.raises(ConfigError, match=error):
        load(_lnc(tmp_path, line))
