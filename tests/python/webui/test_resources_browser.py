"""Resources in the web UI, in a real headless Chromium against the demo robot system
(docs/webui.md, "Resources"): CPU %, RSS and threads in the process table, the host
resources table on the Hosts page, and a resource signal (`process/arm/controller/rss`)
plotted in the scope through the `(resources)` pseudo topic; screenshots under
build/test-artifacts/webui/.  No figure is timed."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from buildtree import not_under_sanitizers
from demo.test_robot_lnc import Demo, demo  # noqa: F401 - fixture

from links_and_nodes.tools.scripting import connect

from .browser import LIMIT, chromium, screenshot, until
from .test_robot_browser import PASSWORD, log_in, show, start_with_webui

CELL = ("return document.querySelector('#process-table tr[data-process=\"arm/controller\"] "
        ".{}').textContent")


@not_under_sanitizers("chromedriver and Chromium abort with the ASan runtime preloaded")
def test_resources_in_chromium(demo: Demo, tmp_path: Path) -> None:  # noqa: F811 - the fixture
    url = start_with_webui(demo, tmp_path)
    driver = chromium()
    try:
        _browse(driver, url)
    finally:
        driver.quit()
    with connect(f"127.0.0.1:{demo.manager_port}", timeout=LIMIT) as mgr:
        mgr.quit()
    assert demo.proc is not None and demo.proc.wait(timeout=LIMIT) == 0, demo.log()


def _browse(driver: Any, url: str) -> None:
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support.ui import Select

    log_in(driver, url, PASSWORD)
    until(lambda: driver.execute_script("return window.lnm && window.lnm.ready"), "the page")
    # the process table: the controller's RSS and threads once a sample came
    until(lambda: driver.execute_script(CELL.format("rss")).endswith("B"), "the RSS column")
    assert int(driver.execute_script(CELL.format("threads"))) >= 1
    # (CPU % needs a second sample of the process)
    cpu = until(lambda: driver.execute_script(CELL.format("cpu")), "the CPU column")
    assert float(cpu) >= 0  # type: ignore[arg-type]
    screenshot(driver, "processes_resources")
    # the hosts page: one row of host resources
    show(driver, "hosts")
    until(lambda: driver.execute_script(
        "return document.querySelectorAll('#host-resources tbody tr').length") == 1,
        "the host resources row")
    heads = driver.execute_script("return [...document.querySelectorAll('#host-resources th')]"
                                  ".map((th) => th.textContent)")
    assert heads[:4] == ["host", "load", "cpu %", "per cpu %"]
    screenshot(driver, "hosts_resources")
    # the scope: a resource signal
    show(driver, "scope")
    until(lambda: "(resources)" in [o.get_attribute("value") for o in
                                    Select(driver.find_element(By.ID, "scope-topic")).options],
          "the resources among the scope's topics")
    Select(driver.find_element(By.ID, "scope-topic")).select_by_value("(resources)")
    signal = "process/arm/controller/rss"
    until(lambda: signal in [o.get_attribute("value") for o in Select(
        driver.find_element(By.ID, "scope-field")).options], "the resource signals")
    Select(driver.find_element(By.ID, "scope-field")).select_by_value(signal)
    driver.find_element(By.ID, "scope-add").click()

    def points() -> list[float] | None:
        b = driver.execute_script("return lnm.scope.buffers()")
        values = [v for v in b[0]["v"][0] if v is not None] if b else []
        return values if len(values) >= 2 else None

    values = until(points, "two points of the RSS signal")
    assert all(v > 0 for v in values)  # type: ignore[union-attr]
    screenshot(driver, "scope_resources")
