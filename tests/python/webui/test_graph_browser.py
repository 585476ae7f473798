"""The web UI's graph page in a real headless Chromium against the demo robot
(examples/robot/robot.lnc): exactly the demo's nodes and edges, the dependency layer when
asked for, the name filter, a subscriber started afterwards appearing with its edge, a
killed process's node changing its state, a click on a topic opening its page; the screenshot goes to
build/test-artifacts/webui/graph.png (docs/images/webui_graph.png is one)."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

from buildtree import not_under_sanitizers
from demo.test_robot_lnc import CONFIG, Demo, demo  # noqa: F401 - fixture

from links_and_nodes.tools.scripting import connect

from .browser import LIMIT, chromium, screenshot, until
from .test_robot_browser import show

PROCESSES = {"p:arm/sensor", "p:arm/controller", "p:supervisor"}
# the controller's parameter block is a service of its own (docs/parameters.md)
NODES = PROCESSES | {"t:arm.state", "t:arm.command", "t:arm.reference", "s:arm.set_gains",
                     "s:arm.controller.parameters.gains"}
EDGES = {("p:arm/sensor", "t:arm.state", "publishes"),
         ("t:arm.state", "p:arm/controller", "subscribes"),
         ("t:arm.state", "p:supervisor", "subscribes"),
         ("p:arm/controller", "t:arm.command", "publishes"),
         ("t:arm.command", "p:arm/sensor", "subscribes"),
         ("p:arm/controller", "t:arm.reference", "publishes"),
         ("t:arm.reference", "p:supervisor", "subscribes"),
         ("p:supervisor", "s:arm.set_gains", "calls"),
         ("s:arm.set_gains", "p:arm/controller", "provides"),
         ("s:arm.controller.parameters.gains", "p:arm/controller", "provides")}
DEPENDS = {("p:arm/controller", "p:arm/sensor", "depends_on"),
           ("p:supervisor", "p:arm/controller", "depends_on")}
WATCHER = """\
import sys, time
import links_and_nodes as ln
clnt = ln.client("graph_watcher", sys.argv[1])
clnt.subscribe("arm.state", "robot/joint_state")
print("ready", flush=True)
time.sleep(3600)
"""


def start(demo: Demo, tmp: Path) -> str:  # noqa: F811 - the fixture
    """robot.lnc with the web UI (no auth file: loopback, no login) and without
    --exit-on-failure, so that a killed process stays failed; its URL once all are ready."""
    demo.env.pop("LNM_WEBUI_AUTH_FILE", None)
    with open(tmp / "manager.log", "w") as log:
        demo.proc = subprocess.Popen(
            [sys.executable, "-m", "links_and_nodes.manager", "-c", str(CONFIG),
             "--instance", demo.instance, "--start-all", "--wait-ready",
             "--ready-timeout", str(LIMIT), "--no-console", "--webui"],
            stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=log, text=True,
            env=demo.env)
    assert "listening on" in demo.stdout_line(), demo.log()
    match = re.match(r"ln_manager: web UI on (http://127\.0\.0\.1:\d+/)$",
                     demo.stdout_line().strip())
    assert match, demo.log()
    assert demo.stdout_line().strip() == "ln_manager: all 3 processes ready", demo.log()
    return match.group(1)


def model(driver: Any) -> dict[str, Any] | None:
    return driver.execute_script("return lnm.views.graph.model()")  # type: ignore[no-any-return]


def shown(driver: Any) -> tuple[set[str], set[tuple[str, str, str]]]:
    m = model(driver) or {"nodes": [], "edges": []}
    return ({n["id"] for n in m["nodes"]},
            {(e["from"], e["to"], e["kind"]) for e in m["edges"]})


def state_of(driver: Any, node: str) -> str:
    m = model(driver) or {"nodes": []}
    return next((n["state"] for n in m["nodes"] if n["id"] == node), "")


@not_under_sanitizers("chromedriver and Chromium abort with the ASan runtime preloaded")
def test_graph_page_in_chromium(demo: Demo, tmp_path: Path) -> None:  # noqa: F811 - fixture
    url = start(demo, tmp_path)
    driver = chromium()
    watcher = None
    try:
        driver.get(url)
        until(lambda: driver.execute_script("return window.lnm && window.lnm.ready"), "the page")
        show(driver, "graph")
        # exactly the demo: processes, topics, the service with its caller and provider
        until(lambda: shown(driver) == (NODES, EDGES)
              and all(state_of(driver, p) == "ready" for p in PROCESSES),
              f"the demo's graph (shown: {shown(driver)})")
        # the dependency layer, when asked for
        driver.find_element("id", "graph-deps").click()
        until(lambda: DEPENDS <= shown(driver)[1], "the dependency edges")
        time.sleep(1.5)  # the rates of the next look in the labels
        screenshot(driver, "graph")
        driver.find_element("id", "graph-deps").click()
        until(lambda: not DEPENDS & shown(driver)[1], "the dependency edges hidden again")

        # the filter: the nodes whose name has the text, and their neighbours
        driver.find_element("id", "graph-filter").send_keys("set_gains")
        until(lambda: shown(driver)[0] == {"s:arm.set_gains", "p:supervisor",
                                           "p:arm/controller"}, "the filtered graph")
        driver.find_element("id", "graph-filter").clear()
        driver.execute_script("document.getElementById('graph-filter')"
                              ".dispatchEvent(new Event('input'))")
        until(lambda: shown(driver)[0] == NODES, "the whole graph again")

        # a new subscriber appears with its edge
        script = tmp_path / "watcher.py"
        script.write_text(WATCHER)
        watcher = subprocess.Popen([sys.executable, str(script),
                                    f"127.0.0.1:{demo.manager_port}"],
                                   stdout=subprocess.PIPE, text=True, env=demo.env)
        assert watcher.stdout is not None and watcher.stdout.readline().strip() == "ready"
        subscribed = time.monotonic()
        until(lambda: ("t:arm.state", "c:graph_watcher", "subscribes") in shown(driver)[1],
              "the new subscriber in the graph")
        print(f"new subscriber shown {time.monotonic() - subscribed:.2f} s after it "
              "subscribed")

        # a killed process turns its node's state, and its edges go
        with connect(f"127.0.0.1:{demo.manager_port}", timeout=LIMIT) as mgr:
            pid = next(p["pid"] for p in mgr.status() if p["name"] == "supervisor")
        os.kill(pid, signal.SIGKILL)
        until(lambda: state_of(driver, "p:supervisor") not in ("", "ready"),
              "the supervisor's node leaving 'ready'")
        until(lambda: not {e for e in shown(driver)[1] if "p:supervisor" in e[:2]
                           and e[2] != "depends_on"}, "the supervisor's edges gone")

        # a click on a topic opens its page
        driver.execute_script("document.querySelector('#graph-canvas g[data-id=\"t:arm.state\"]')"
                              ".dispatchEvent(new MouseEvent('click', {bubbles: true}))")
        until(lambda: driver.find_element("id", "view-topics").is_displayed()
              and driver.find_element("id", "topic-title").text == "arm.state",
              "the topic's page")
    finally:
        driver.quit()
        if watcher is not None:
            watcher.kill()
            watcher.wait()
            assert watcher.stdout is not None
            watcher.stdout.close()
