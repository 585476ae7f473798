"""The web UI over TLS in a real headless Chromium: a manager whose instance section names a
self-signed certificate (made by the test for robot.test and 127.0.0.1) and an auth file;
a Chromium that trusts exactly that key (--ignore-certificate-errors-spki-list, every other
certificate check stays on) and resolves robot.test to 127.0.0.1 logs in at
https://robot.test:PORT/, gets a Secure cookie and HSTS, and runs the live page over wss
(a process started by a click, its state live).
A Chromium without that trust is stopped at the certificate.  Screenshot:
build/test-artifacts/webui/tls.png."""

from __future__ import annotations

import re
from typing import Any

from buildtree import not_under_sanitizers
from process_management.conftest import Lab, lab  # noqa: F401 - fixture

from links_and_nodes.manager.frontends.webui.auth import hash_password

from .browser import chromium, screenshot, until
from .certs import Cert, self_signed
from .test_robot_browser import PASSWORD, click, log_in, states

NAME = "robot.test"  # reserved for tests (RFC 6761): never a real host


def start(lab: Lab) -> tuple[int, Cert]:  # noqa: F811 - the fixture
    """A manager with the web UI over TLS on a free port of its own (all from the instance
    section); that port and the certificate."""
    cert = self_signed(lab.tmp / "tls", names=(f"DNS:{NAME}", "IP:127.0.0.1"))
    users = lab.tmp / "webui_users"
    users.write_text(f"operator {hash_password(PASSWORD, n=1 << 10)}\n")
    users.chmod(0o600)
    config = lab.tmp / "tls.lnc"
    config.write_text(f"instance\nname: {lab.instance}\nmanager: 127.0.0.1:{lab.manager_port}\n"
                      f"webui_port: 0\nwebui_auth_file: {users}\nwebui_tls_cert: {cert.cert}\n"
                      f"webui_tls_key: {cert.key}\n\n"
                      f"process idle\ncommand: /bin/sleep 3600 {lab.instance}\n")
    proc = lab.manager(config, "--no-console")
    lab.wait_listening(proc)
    assert proc.stdout is not None
    line = proc.stdout.readline().strip()
    match = re.fullmatch(r"ln_manager: web UI on https://127\.0\.0\.1:(\d+)/", line)
    assert match, f"{line!r}\n{lab.log()}"
    return int(match.group(1)), cert


def _browse(driver: Any, url: str, port: int) -> None:
    log_in(driver, url, PASSWORD)
    until(lambda: driver.execute_script("return window.lnm && window.lnm.ready"), "the page")
    assert driver.execute_script("return location.origin") + "/" == url
    until(lambda: driver.execute_script("return [lnm.api.ws.url, lnm.api.ws.readyState]")
          == [f"wss://{NAME}:{port}/ws", 1], "the WebSocket open over wss")
    until(lambda: states(driver).get("idle") == "stopped", "the process table")
    click(driver, "start", "idle")  # a command with the CSRF token; its transition's event
    until(lambda: states(driver)["idle"] != "stopped", "the start, live over wss")
    cookie = driver.get_cookie("lnm_session")
    assert cookie is not None and cookie["secure"] and cookie["httpOnly"] and \
        cookie["sameSite"] == "Strict"
    hsts = driver.execute_script("return fetch('/api/session').then("
                                 "(r) => [r.status, r.headers.get('strict-transport-security')])")
    assert hsts == [200, "max-age=31536000"]
    screenshot(driver, "tls")


@not_under_sanitizers("chromedriver and Chromium abort with the ASan runtime preloaded")
def test_web_ui_over_tls_in_chromium(lab: Lab) -> None:  # noqa: F811 - the fixture
    port, cert = start(lab)
    url = f"https://{NAME}:{port}/"
    resolve = f"--host-resolver-rules=MAP {NAME} 127.0.0.1"
    driver = chromium(args=(f"--ignore-certificate-errors-spki-list={cert.spki}", resolve))
    try:
        _browse(driver, url, port)
    finally:
        driver.quit()
    untrusting = chromium(args=(resolve,))
    try:
        untrusting.get(url)
        until(lambda: "ERR_CERT_AUTHORITY_INVALID" in untrusting.page_source,
              "the certificate refused without the SPKI trust")
        assert not untrusting.execute_script("return !!window.lnm")
    finally:
        untrusting.quit()
