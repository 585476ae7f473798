"""The web UI's Logs page in a real headless Chromium: the lines a C client logged are
there with level, process, host and file:line, the level filter keeps warning and above, a
line logged afterwards appears live, and the text filter narrows to it; the screenshot goes
to build/test-artifacts/webui/logs.png (docs/images/webui_logs.png is one)."""

from __future__ import annotations

import logging
import re
import subprocess
import uuid
from typing import Any

from buildtree import not_under_sanitizers
from logs.conftest import LIMIT, LOG_TOOL
from process_management.conftest import Lab, lab  # noqa: F401 - fixture

import links_and_nodes as ln

from .browser import chromium, screenshot, until
from .test_robot_browser import show


def start(lab: Lab) -> tuple[str, str]:  # noqa: F811 - the fixture
    """A manager with a configuration (the web UI needs one) of one idle process: its
    address and the web UI's URL."""
    config = lab.write(f"process idle\ncommand: /bin/sleep 3600 {lab.instance}\n\n")
    proc = lab.manager(config, "--no-console", "--webui")
    address = lab.wait_listening(proc)
    assert proc.stdout is not None
    match = re.match(r"ln_manager: web UI on (http://127\.0\.0\.1:\d+/)$",
                     proc.stdout.readline().strip())
    assert match, lab.log()
    return address, match.group(1)


def rows(driver: Any) -> list[list[str]]:
    from selenium.webdriver.common.by import By

    return [[td.text for td in tr.find_elements(By.TAG_NAME, "td")]
            for tr in driver.find_elements(By.CSS_SELECTOR, "#logs-table tbody tr")]


@not_under_sanitizers("chromedriver and Chromium abort with the ASan runtime preloaded")
def test_logs_page_in_chromium(lab: Lab) -> None:  # noqa: F811 - the fixture
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support.ui import Select

    address, url = start(lab)
    driver = None
    try:
        name = f"logweb{uuid.uuid4().hex[:6]}"
        done = subprocess.run([str(LOG_TOOL), "levels", name], capture_output=True, text=True,
                              env={**lab.env, "LN_MANAGER": address}, timeout=LIMIT)
        assert done.returncode == 0 and done.stdout.endswith("flushed\n"), done
        driver = chromium()
        driver.get(url)
        until(lambda: driver.execute_script("return window.lnm && window.lnm.ready"), "the page")
        show(driver, "logs")
        until(lambda: len(rows(driver)) == 6, "the six lines of the C client")
        first = rows(driver)[0]
        assert first[1] == "debug" and first[2] == name and first[3]
        assert re.fullmatch(r"log_tool\.c:\d+", first[4]) and first[5] == \
            "c line at level 10: ok"
        Select(driver.find_element(By.ID, "logs-level")).select_by_value("warning")
        until(lambda: [r[1] for r in rows(driver)] == ["warning", "error", "critical"],
              "warning and above only")
        # a line logged now appears live, through the level filter
        clnt = ln.client("web_live", address)
        logger = logging.getLogger("test.webui.logs")
        logger.propagate = False
        logger.setLevel(logging.DEBUG)
        handler = ln.LogHandler(clnt)
        logger.addHandler(handler)
        try:
            logger.error("live line from python")
            logger.info("idle, waiting for a goal")  # below the page's level for now
            handler.flush(60.0)
        finally:
            logger.removeHandler(handler)
            clnt.close()
        until(lambda: [r[5] for r in rows(driver)][-1:] ==
              ["[test.webui.logs] live line from python"], "the live line")
        assert len(rows(driver)) == 4
        driver.find_element(By.ID, "logs-text").send_keys("LIVE")
        until(lambda: [r[2] for r in rows(driver)] == ["web_live"], "the text filter")
        driver.find_element(By.ID, "logs-text").clear()
        driver.execute_script("document.getElementById('logs-text')"
                              ".dispatchEvent(new Event('input'))")
        until(lambda: len(rows(driver)) == 4, "the text filter cleared")
        Select(driver.find_element(By.ID, "logs-level")).select_by_value("debug")
        until(lambda: len(rows(driver)) == 8, "every line again")
        screenshot(driver, "logs")
    finally:
        if driver is not None:
            driver.quit()
