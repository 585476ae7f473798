"""A real headless Chromium for the web UI's end-to-end tests: Debian's chromium and
chromium-driver (scripts/setup installs them) driven by PyPI selenium
(requirements-dev.txt).  Screenshots go to build/test-artifacts/webui/."""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from buildtree import REPO, missing_test_tool

CHROMIUM = Path("/usr/bin/chromium")
DRIVER = Path("/usr/bin/chromedriver")
ARTIFACTS = REPO / "build" / "test-artifacts" / "webui"
LIMIT = 60.0  # seconds for anything to happen, never a measurement


def chromium(width: int = 1400, height: int = 900, args: tuple[str, ...] = ()) -> Any:
    """A headless Chromium WebDriver (quit() it), with more command line `args`; a missing
    tool fails under CI."""
    try:
        from selenium import webdriver
        from selenium.webdriver.chrome.service import Service
    except ImportError:
        missing_test_tool("the Python package selenium (requirements-dev.txt)")
    if not CHROMIUM.exists() or not DRIVER.exists():
        missing_test_tool("Debian's chromium and chromium-driver (scripts/setup)")
    options = webdriver.ChromeOptions()
    options.binary_location = str(CHROMIUM)
    for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                f"--window-size={width},{height}", "--disable-extensions",
                "--no-first-run", "--password-store=basic", *args):
        options.add_argument(arg)
    return webdriver.Chrome(service=Service(str(DRIVER)), options=options)


def until(predicate: Callable[[], Any], what: str, timeout: float = LIMIT) -> Any:
    """The first truthy value of predicate(); AssertionError after `timeout` seconds."""
    deadline = time.monotonic() + timeout
    last: Any = None
    while time.monotonic() < deadline:
        try:
            last = predicate()
        except Exception as exc:  # noqa: BLE001 - the page may be between two states
            last = exc
        if last and not isinstance(last, Exception):
            return last
        time.sleep(0.1)
    raise AssertionError(f"{what}: not within {timeout} s (last: {last!r})")


def screenshot(driver: Any, name: str) -> Path:
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    path = ARTIFACTS / f"{name}.png"
    driver.save_screenshot(str(path))
    return path
