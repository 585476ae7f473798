"""The web UI end to end in a real headless Chromium against the demo robot system
(examples/robot/robot.lnc run by `ln_manager --webui` with an auth file, the web UI on the
manager's own port): log in (a wrong password refused), the three processes ready, stop
and start the controller by clicking, follow the supervisor's output, plot arm.state
position[0..6] in the scope and read the points from the page's buffers; screenshots of
every view under build/test-artifacts/webui/.  Against the same manager: a missing cookie,
a missing CSRF token and a foreign Origin are refused, and the binary clients keep working
on the shared port."""

from __future__ import annotations

import json
import re
import subprocess
import sys
import time
import urllib.error
import urllib.request
from pathlib import Path
from typing import Any

from buildtree import not_under_sanitizers
from demo.test_robot_lnc import CONFIG, Demo, demo  # noqa: F401 - fixture

from links_and_nodes.manager.frontends.webui.auth import hash_password
from links_and_nodes.tools.scripting import connect

from .browser import LIMIT, chromium, screenshot, until

PASSWORD = "correct horse battery"
SCOPE_FIELDS = [f"position[{i}]" for i in range(7)]


def start_with_webui(demo: Demo, tmp: Path) -> str:  # noqa: F811 - the fixture
    """Start robot.lnc with the web UI; its URL once every process is ready."""
    users = tmp / "webui_users"
    users.write_text(f"operator {hash_password(PASSWORD)}\n")
    users.chmod(0o600)
    demo.env["LNM_WEBUI_AUTH_FILE"] = str(users)
    with open(tmp / "manager.log", "w") as log:
        demo.proc = subprocess.Popen(
            [sys.executable, "-m", "links_and_nodes.manager", "-c", str(CONFIG),
             "--instance", demo.instance, "--start-all", "--wait-ready",
             "--ready-timeout", str(LIMIT), "--exit-on-failure", "--no-console", "--webui"],
            stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=log, text=True,
            env=demo.env)
    assert "listening on" in demo.stdout_line(), demo.log()
    line = demo.stdout_line()
    match = re.match(r"ln_manager: web UI on (http://127\.0\.0\.1:(\d+)/)$", line.strip())
    assert match and int(match.group(2)) == demo.manager_port, f"{line!r}\n{demo.log()}"
    assert demo.stdout_line().strip() == "ln_manager: all 3 processes ready", demo.log()
    return match.group(1)


def states(driver: Any) -> dict[str, str]:
    return driver.execute_script(
        "const out = {};"
        "for (const tr of document.querySelectorAll('#process-table tr[data-process]'))"
        "  out[tr.dataset.process] = tr.querySelector('.state').textContent;"
        "return out;")


def click(driver: Any, action: str, target: str) -> None:
    """Click a process's button (again if the table was redrawn between finding and
    clicking it: it is redrawn at every transition)."""
    from selenium.common.exceptions import StaleElementReferenceException
    from selenium.webdriver.common.by import By

    def once() -> bool:
        try:
            driver.find_element(By.CSS_SELECTOR, f"#process-table button[data-action="
                                                 f"'{action}'][data-target='{target}']").click()
        except StaleElementReferenceException:
            return False
        return True

    until(once, f"a click on {action} {target}")


def show(driver: Any, view: str) -> None:
    from selenium.webdriver.common.by import By

    driver.find_element(By.CSS_SELECTOR, f"#tabs button[data-view='{view}']").click()
    until(lambda: driver.find_element(By.ID, f"view-{view}").is_displayed(), f"view {view}")


def log_in(driver: Any, url: str, password: str) -> None:
    from selenium.webdriver.common.by import By

    driver.get(url)
    user = until(lambda: driver.find_element(By.ID, "user"), "the login form")
    user.clear()
    user.send_keys("operator")
    field = driver.find_element(By.ID, "password")
    field.clear()
    field.send_keys(password)
    driver.find_element(By.ID, "login-button").click()


@not_under_sanitizers("chromedriver and Chromium abort with the ASan runtime preloaded; the "
                      "manager's web UI server is Python, run by the other web UI tests")
def test_web_ui_in_chromium(demo: Demo, tmp_path: Path) -> None:  # noqa: F811 - the fixture
    url = start_with_webui(demo, tmp_path)
    driver = chromium()
    try:
        _browse(driver, url)
    finally:
        driver.quit()
    _refusals(url, demo)
    with connect(f"127.0.0.1:{demo.manager_port}", timeout=LIMIT) as mgr:
        assert {p["state"] for p in mgr.status()} == {"ready"}
        mgr.quit()
    assert demo.proc is not None and demo.proc.wait(timeout=LIMIT) == 0, demo.log()


def _browse(driver: Any, url: str) -> None:
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support.ui import Select

    log_in(driver, url, "wrong password")
    until(lambda: "wrong user or password" in driver.find_element(By.ID, "login-error").text,
          "the refusal of a wrong password")
    assert driver.get_cookies() == []
    screenshot(driver, "login")
    log_in(driver, url, PASSWORD)
    until(lambda: driver.execute_script("return window.lnm && window.lnm.ready"), "the page")
    cookie = driver.get_cookie("lnm_session")
    assert cookie is not None and cookie["httpOnly"] and cookie["sameSite"] == "Strict"

    # processes: three ready; stop the controller (the supervisor, its dependent, first)
    until(lambda: states(driver) == {"arm/sensor": "ready", "arm/controller": "ready",
                                     "supervisor": "ready"}, "three processes ready")
    screenshot(driver, "processes")
    click(driver, "stop", "arm/controller")
    until(lambda: states(driver)["arm/controller"] == "stopped"
          and states(driver)["supervisor"] == "stopped", "controller and supervisor stopped")
    assert states(driver)["arm/sensor"] == "ready"
    # the dependency view: the supervisor waits on the controller it depends on
    until(lambda: driver.execute_script(
        "return document.querySelector('#process-table tr[data-process=\"supervisor\"] "
        ".waiting').textContent") == "arm/controller", "the supervisor waiting on the controller")
    screenshot(driver, "processes_stopped")
    click(driver, "start", "arm/controller")
    until(lambda: states(driver)["arm/controller"] == "ready", "the controller ready again")
    click(driver, "start", "supervisor")
    until(lambda: states(driver)["supervisor"] == "ready", "the supervisor ready again")

    # the supervisor's output, followed live, and its state history
    show(driver, "output")
    Select(driver.find_element(By.ID, "output-process")).select_by_value("supervisor")
    pattern = re.compile(r"t=\d+ s tracking error rms")
    before = until(lambda: len(pattern.findall(driver.find_element(By.ID, "output-lines").text)),
                   "the supervisor's tracking error")
    until(lambda: len(pattern.findall(driver.find_element(By.ID, "output-lines").text)) > before,
          "a new line of the supervisor, followed")
    history = driver.find_element(By.ID, "output-history").text
    assert "stopped" in history and "ready" in history, history
    screenshot(driver, "output")

    # the scope: arm.state position[0..6]
    show(driver, "scope")
    until(lambda: "arm.state" in [o.get_attribute("value") for o in
                                  Select(driver.find_element(By.ID, "scope-topic")).options],
          "arm.state among the scope's topics")
    Select(driver.find_element(By.ID, "scope-topic")).select_by_value("arm.state")
    until(lambda: "position[6]" in [o.get_attribute("value") for o in Select(
        driver.find_element(By.ID, "scope-field")).options], "the fields of arm.state")
    fields = Select(driver.find_element(By.ID, "scope-field"))
    for name in SCOPE_FIELDS:
        fields.select_by_value(name)
    driver.find_element(By.ID, "scope-add").click()
    first = until(lambda: _scope(driver, 200), "points in the scope")
    assert first["fields"] == SCOPE_FIELDS and len(first["v"]) == 7
    assert all(len(col) == len(first["t"]) for col in first["v"])
    later = until(lambda: (b := _scope(driver, 1)) and b["t"][-1] > first["t"][-1] + 0.5 and b,
                  "publish times advancing")
    t = later["t"]
    assert all(b > a for a, b in zip(t, t[1:], strict=False)), "publish times not increasing"
    # at the topic's rate (1 kHz), loosely: at least 100 points per second of publish time
    assert len(t) / (t[-1] - t[0]) > 100, (len(t), t[-1] - t[0])
    assert driver.execute_script("return lnm.scope.frames") > 0
    time.sleep(0.5)
    screenshot(driver, "scope")

    for view in ("topics", "services", "params", "hosts", "log"):
        show(driver, view)
        if view == "topics":
            until(lambda: driver.find_element(By.CSS_SELECTOR, "tr[data-topic='arm.state']"),
                  "arm.state").click()
            until(lambda: '"position"' in driver.find_element(By.ID, "topic-values").text,
                  "arm.state's decoded values")
            until(lambda: "Hz" in driver.find_element(
                By.CSS_SELECTOR, "tr[data-topic='arm.state']").text, "the topic's rate")
        if view == "services":
            until(lambda: driver.find_element(By.CSS_SELECTOR,
                                              "tr[data-service='arm.set_gains']"),
                  "arm.set_gains").click()
            until(lambda: driver.find_element(By.NAME, "kp"), "the request form")
            # the form calls the service: the controller's own limits answer
            driver.find_element(By.NAME, "kp").send_keys(json.dumps([5000.0] * 7))
            driver.find_element(By.NAME, "kd").send_keys(json.dumps([10.0] * 7))
            driver.find_element(By.NAME, "profile_name").send_keys("webui")
            driver.find_element(By.CSS_SELECTOR, "#service-form button[type=submit]").click()
            answer = until(lambda: driver.find_element(By.ID, "service-response").text,
                           "the service's answer")
            assert "kp[0] = 5000 Nm/rad is outside (0, 1000]" in answer, answer
        if view == "params":
            until(lambda: driver.find_element(By.CSS_SELECTOR, "tr[data-param='kp']"),
                  "the gains block")
        if view == "log":
            until(lambda: "arm/controller" in driver.find_element(By.ID, "log-lines").text,
                  "the manager's messages")
        time.sleep(0.3)
        screenshot(driver, view)


def _scope(driver: Any, least: int) -> dict[str, Any] | None:
    buffers = driver.execute_script("return lnm.scope.buffers()")
    if len(buffers) != 1 or len(buffers[0]["t"]) < least:
        return None
    return buffers[0]  # type: ignore[no-any-return]


def _refusals(url: str, demo: Demo) -> None:  # noqa: F811 - the fixture
    """Wrong password, missing cookie, missing CSRF token, foreign Origin."""
    import base64

    def status(req: urllib.request.Request) -> int:
        try:
            with urllib.request.urlopen(req, timeout=LIMIT) as answer:
                return int(answer.status)
        except urllib.error.HTTPError as exc:
            return exc.code

    basic = base64.b64encode(b"operator:nope").decode()
    assert status(urllib.request.Request(url + "login", method="POST",
                                         headers={"Authorization": f"Basic {basic}"})) == 401
    assert status(urllib.request.Request(url + "api/session")) == 401
    basic = base64.b64encode(f"operator:{PASSWORD}".encode()).decode()
    with urllib.request.urlopen(urllib.request.Request(
            url + "login", method="POST", headers={"Authorization": f"Basic {basic}"}),
            timeout=LIMIT) as answer:
        cookie = answer.headers["Set-Cookie"].split(";")[0]
    stop = json.dumps({"op": "stop", "target": "arm/controller"}).encode()
    assert status(urllib.request.Request(url + "api/command", data=stop, method="POST",
                                         headers={"Cookie": cookie})) == 403
    assert status(urllib.request.Request(url + "api/command", data=stop, method="POST",
                                         headers={"Cookie": cookie, "X-CSRF-Token": "x"})) \
        == 403
    with urllib.request.urlopen(urllib.request.Request(url + "api/session",
                                                       headers={"Cookie": cookie}),
                                timeout=LIMIT) as answer:
        assert json.loads(answer.read())["user"] == "operator"
    upgrade = {"Cookie": cookie, "Upgrade": "websocket", "Connection": "Upgrade",
               "Sec-WebSocket-Version": "13", "Sec-WebSocket-Key": "dGhlIHNhbXBsZSBub25jZQ==",
               "Origin": "http://evil.example"}
    assert status(urllib.request.Request(url + "ws", headers=upgrade)) == 403
    with connect(f"127.0.0.1:{demo.manager_port}", timeout=LIMIT) as mgr:
        assert mgr.status()[1]["state"] == "ready"  # the refused stop changed nothing

