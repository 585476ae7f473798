"""`ln_services` end to end: a real ln_manager with fake providers (lnwire) listed as a
table and as JSON, the manager taken from --manager or $LN_MANAGER; one-line errors and
exit status 1 for an unreachable manager and for a manager answering ERROR (a fake one,
written with struct), and the note when the list was cut at the frame limit."""

from __future__ import annotations

import json
import os
import re
import socket
import struct
import subprocess
import sys
import threading
import tomllib
from collections.abc import Callable, Iterator

import lnwire
import pytest
from mgrproc import REPO, WAIT, Manager, require_manager_library

from links_and_nodes.addresses import parse_manager_address
from links_and_nodes.manager.frontends import listing

require_manager_library()

Start = Callable[..., Manager]
MD = "robot/move"
HASH = 0x0123456789ABCDEF
SIG = "robot/move_request|robot/move_response"


def ln_services(*args: str,
                env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    """Run `python -m links_and_nodes.manager.frontends.listing ARGS` (what the ln_services script
    runs) in the source tree."""
    path = [str(REPO / "python"), *filter(None, [os.environ.get("PYTHONPATH")])]
    full_env = dict(os.environ if env is None else env, PYTHONPATH=os.pathsep.join(path))
    return subprocess.run([sys.executable, "-m", "links_and_nodes.manager.frontends.listing", *args],
                          capture_output=True, text=True, env=full_env, timeout=WAIT,
                          cwd=REPO)


def register(client: lnwire.WireClient, name: str, **kwargs: object) -> None:
    md = str(kwargs.pop("md", MD))
    reply = client.register_service(name, md, HASH, SIG, **kwargs)
    assert reply.type == lnwire.OK, reply


@pytest.fixture
def providers(manager: Manager) -> Iterator[Manager]:
    """The manager with three services of two providers, with counts."""
    prov = manager.client("arm_ctl")
    gripper = manager.client("gripper")
    register(prov, "arm.move", group="arm", host_id="host-a",
             unix_path="/run/ln/svc.10.1.sock", tcp_host="10.0.0.5", tcp_port=40123)
    register(prov, "arm.set_gains", md="robot/set_gains", tcp_host="10.0.0.5",
             tcp_port=40125)
    register(gripper, "Gripper.open", unix_path="/run/ln/svc.11.1.sock", group="tools")
    assert prov.service_called("arm.move", 12, 1).type == lnwire.OK
    assert gripper.service_called("Gripper.open", 3, 0).type == lnwire.OK
    yield manager
    prov.close()
    gripper.close()


def test_table(providers: Manager) -> None:
    result = ln_services("--manager", f"127.0.0.1:{providers.port}")
    assert (result.returncode, result.stderr) == (0, "")
    lines = result.stdout.splitlines()
    assert lines[0].split() == list(listing.COLUMNS)
    assert [line.split() for line in lines[1:]] == [
        ["Gripper.open", "gripper", MD, "tools", "3", "0", "unix:/run/ln/svc.11.1.sock"],
        ["arm.move", "arm_ctl", MD, "arm", "12", "1", "unix:/run/ln/svc.10.1.sock",
         "tcp:10.0.0.5:40123"],
        ["arm.set_gains", "arm_ctl", "robot/set_gains", "-", "0", "0", "tcp:10.0.0.5:40125"],
    ]
    # columns line up: every row's fields start where the header's do
    starts = [m.start() for m in re.finditer(r"\S+", lines[0])]
    for line in lines[1:]:
        assert [m.start() for m in re.finditer(r"\S+", line)][:6] == starts[:6]
    providers.wait_log(r"client ln_services \(.*\): connected")


def test_json_from_ln_manager_variable(providers: Manager) -> None:
    env = dict(os.environ, LN_MANAGER=f"127.0.0.1:{providers.port}")
    result = ln_services("--json", env=env)
    assert (result.returncode, result.stderr) == (0, "")
    services = json.loads(result.stdout)
    assert [s["name"] for s in services] == ["Gripper.open", "arm.move", "arm.set_gains"]
    assert services[1] == {
        "name": "arm.move", "md_name": MD, "layout_hash": "0x0123456789abcdef",
        "provider": "arm_ctl", "group": "arm", "host_id": "host-a",
        "unix_path": "/run/ln/svc.10.1.sock", "tcp_host": "10.0.0.5", "tcp_port": 40123,
        "calls": 12, "errors": 1}
    assert (services[2]["unix_path"], services[2]["tcp_port"]) == ("", 40125)


def test_no_services(manager: Manager, capsys: pytest.CaptureFixture[str]) -> None:
    # in-process, through main(argv) as the console script calls it
    assert listing.main(["--manager", f":{manager.port}"]) == 0
    assert capsys.readouterr() == ("no services\n", "")
    assert listing.main(["--manager", f"127.0.0.1:{manager.port}", "--json"]) == 0
    assert json.loads(capsys.readouterr().out) == []


def _free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


def test_unreachable_manager() -> None:
    port = _free_port()
    result = ln_services("--manager", f"127.0.0.1:{port}")
    assert result.returncode == 1
    assert result.stdout == ""
    assert result.stderr == (f"ln_services: error: cannot reach the manager at "
                             f"127.0.0.1:{port}: Connection refused\n")


@pytest.mark.parametrize("args, env, text", [
    ([], {}, "no manager address: give --manager HOST:PORT or set LN_MANAGER"),
    (["--manager", "localhost"], {}, "bad manager address 'localhost'"),
    ([], {"LN_MANAGER": "::1:5"}, "bad manager address '::1:5'"),
    (["--manager", "h:70000"], {}, "with a port 1..65535"),
])
def test_bad_addresses(args: list[str], env: dict[str, str], text: str) -> None:
    base = {k: v for k, v in os.environ.items() if k != "LN_MANAGER"}
    result = ln_services(*args, env={**base, **env})
    assert result.returncode == 2
    assert text in result.stderr.splitlines()[-1]


@pytest.mark.parametrize("text, address", [
    ("h:1", ("h", 1)), (":54414", ("localhost", 54414)), ("[::1]:80", ("::1", 80)),
    ("10.0.0.1:65535", ("10.0.0.1", 65535)),
])
def test_parse_address(text: str, address: tuple[str, int]) -> None:
    assert parse_manager_address(text) == address


class FakeManager:
    """Accepts one connection and answers each frame type from `answers` (raw frames)."""

    def __init__(self, answers: dict[int, bytes]) -> None:
        self.answers = answers
        self.received: list[int] = []
        self.sock = socket.create_server(("127.0.0.1", 0))
        self.port = self.sock.getsockname()[1]
        self.thread = threading.Thread(target=self._serve, daemon=True)
        self.thread.start()

    def _serve(self) -> None:
        conn, _ = self.sock.accept()
        with conn:
            while True:
                header = conn.recv(6, socket.MSG_WAITALL)
                if len(header) < 6:
                    return
                length, type_ = struct.unpack("<IH", header)
                if length > 2:
                    conn.recv(length - 2, socket.MSG_WAITALL)
                self.received.append(type_)
                conn.sendall(self.answers[type_])

    def close(self) -> None:
        self.sock.close()
        self.thread.join(WAIT)


WELCOME = lnwire.frame(lnwire.WELCOME, struct.pack("<HI", 1, 7) + lnwire.s("ln_services")
                       + lnwire.s("inst"))


def error_frame(request_id: int, code: int, text: str) -> bytes:
    return lnwire.frame(lnwire.ERROR, struct.pack("<Ii", request_id, code) + lnwire.s(text))


@pytest.mark.parametrize("answers, message", [
    ({lnwire.HELLO: error_frame(0, -7, "client speaks protocol 1, manager speaks 2")},
     r"the manager refused HELLO: LN_EVERSION: client speaks protocol 1, "
     r"manager speaks 2"),
    ({lnwire.HELLO: WELCOME, lnwire.LIST_SERVICES: error_frame(1, -9, "no list today")},
     r"the manager refused LIST_SERVICES: LN_ENOTFOUND: no list today"),
    ({lnwire.HELLO: WELCOME, lnwire.LIST_SERVICES: error_frame(1, -999, "odd")},
     r"the manager refused LIST_SERVICES: error -999: odd"),
    ({lnwire.HELLO: WELCOME, lnwire.LIST_SERVICES: lnwire.frame(lnwire.OK, b"\1\0\0\0")},
     r"the manager answered LIST_SERVICES with OK, expected SERVICE_LIST"),
    ({lnwire.HELLO: WELCOME, lnwire.LIST_SERVICES: lnwire.frame(
        lnwire.SERVICE_LIST, struct.pack("<III", 1, 1, 1))},
     r"malformed answer from the manager: SERVICE_LIST body too short: 12 bytes, ends "
     r"inside the length of entries\[0\]\.name"),
])
def test_manager_answers_an_error(answers: dict[int, bytes], message: str) -> None:
    fake = FakeManager(answers)
    try:
        result = ln_services("--manager", f"127.0.0.1:{fake.port}")
    finally:
        fake.close()
    assert result.returncode == 1
    assert result.stdout == ""
    assert re.fullmatch(rf"ln_services: error: {message}\n", result.stderr), result.stderr


def test_a_cut_list_says_so() -> None:
    entry = (lnwire.s("a.svc") + lnwire.s(MD) + struct.pack("<Q", HASH) + lnwire.s("prov")
             + lnwire.s("") + lnwire.s("") + lnwire.s("") + lnwire.s("h")
             + struct.pack("<HQQ", 5, 0, 0))
    fake = FakeManager({lnwire.HELLO: WELCOME, lnwire.LIST_SERVICES: lnwire.frame(
        lnwire.SERVICE_LIST, struct.pack("<III", 1, 400, 1) + entry)})
    try:
        result = ln_services("--manager", f"127.0.0.1:{fake.port}")
    finally:
        fake.close()
    assert result.returncode == 0
    assert result.stdout.splitlines()[1].split() == ["a.svc", "prov", MD, "-", "0", "0",
                                                      "tcp:h:5"]
    assert result.stderr == ("ln_services: showing 1 of 400 services: the list did not fit "
                             "one frame\n")
    assert fake.received == [lnwire.HELLO, lnwire.LIST_SERVICES]


def test_console_script_is_declared_for_pip_and_scons() -> None:
    scripts = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]["scripts"]
    assert scripts["ln_services"] == "links_and_nodes.manager.frontends.listing:main"
    sconscript = (REPO / "python" / "SConscript").read_text()
    assert "('ln_services', 'links_and_nodes.manager.frontends.listing')" in sconscript


def test_table_cells_are_one_line() -> None:
    from links_and_nodes.tools import protocol as p

    entry = p.ServiceEntry("s", "m", 1, "a b", "g\nh\t", "", "/x", "::1", 9, 0, 0)
    [header, row] = listing.table((entry,))
    assert re.split(r"\s{2,}", row) == ["s", "a b", "m", "g\\nh\\t", "0", "0",
                                        "unix:/x tcp:[::1]:9"]
    assert re.split(r"\s{2,}", header) == list(listing.COLUMNS)
