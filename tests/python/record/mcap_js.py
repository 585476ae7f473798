"""The second independent MCAP reader of the recording tests: Foxglove's TypeScript library
(@mcap/core with @mcap/support's decompressors) under Node.js, run by mcap_js/check_mcap.mjs;
and Foxglove's ROS 2 decoding (@foxglove/rosmsg, @foxglove/rosmsg2-serialization), run by
mcap_js/decode_ros2.mjs.

It is installed with npm into build/mcap_js (once; a lock keeps parallel workers from
installing it twice).  Where Node.js or npm is missing or the install fails,
buildtree.missing_test_tool decides: a failure in CI's main run, a skip elsewhere."""

from __future__ import annotations

import fcntl
import json
import shutil
import subprocess
from pathlib import Path
from typing import Any, NoReturn

from buildtree import missing_test_tool

HERE = Path(__file__).resolve().parent / "mcap_js"
TARGET = Path(__file__).resolve().parents[3] / "build" / "mcap_js"


def _unavailable(why: str) -> NoReturn:
    missing_test_tool(f"the TypeScript MCAP reader ({why})")


def _installed() -> Path:
    if shutil.which("node") is None or shutil.which("npm") is None:
        _unavailable("node and npm are not installed")
    TARGET.mkdir(parents=True, exist_ok=True)
    with open(TARGET.parent / "mcap_js.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        wanted = (HERE / "package.json").read_bytes()
        stamp = TARGET / "node_modules" / ".ln-package.json"
        if not (stamp.exists() and stamp.read_bytes() == wanted):
            shutil.copy(HERE / "package.json", TARGET / "package.json")
            try:
                done = subprocess.run(
                    ["npm", "install", "--no-audit", "--no-fund", "--no-package-lock",
                     "--ignore-scripts", "--loglevel=error"], cwd=TARGET, capture_output=True,
                    text=True, timeout=300, stdin=subprocess.DEVNULL)
            except subprocess.TimeoutExpired:
                _unavailable("npm install took longer than 300 s")
            if done.returncode != 0:
                _unavailable(f"npm install failed: {done.stderr.strip()[-2000:]}")
            stamp.write_bytes(wanted)
        for script in HERE.glob("*.mjs"):
            shutil.copy(script, TARGET / script.name)
    return TARGET


def js_read(*files: Path) -> dict[str, Any]:
    """What @mcap/core read from each file: {path: {done, leftover, messages: [[topic, seq,
    publish_time, log_time, data hex]], schemas, channels, indexed?}}; fails the test with
    the reader's error when it rejects a file."""
    return _node("check_mcap.mjs", files, "@mcap/core rejected")


def js_decode_ros2(*files: Path) -> dict[str, Any]:
    """The ros2 channels of each file as Foxglove's readers decode them: {path: {topic:
    {schema, schema_encoding, message_encoding, messages: [[seq, log_time, value,
    trailing bytes]]}}}, value a dict of the ROS 2 field names (a 64-bit integer exact,
    -0.0 kept, NaN and ±Infinity as "NaN", "Infinity", "-Infinity"); {path: {"error": text}}
    for a file, schema or message it cannot read."""
    return _node("decode_ros2.mjs", files, "decode_ros2.mjs failed on")


def _node(script: str, files: tuple[Path, ...], failed: str) -> dict[str, Any]:
    """The JSON that `script` prints for `files`; fails the test with its stderr."""
    target = _installed()
    done = subprocess.run(["node", str(target / script), *map(str, files)],
                          capture_output=True, text=True, timeout=300, cwd=target)
    assert done.returncode == 0, f"{failed} {files}: {done.stderr}"
    result: dict[str, Any] = json.loads(done.stdout)
    return result


def js_rejects(path: Path) -> str:
    """@mcap/core's error for a file it must reject (the test fails if it accepts it)."""
    target = _installed()
    done = subprocess.run(["node", str(target / "check_mcap.mjs"), str(path)],
                          capture_output=True, text=True, timeout=300, cwd=target)
    assert done.returncode != 0, f"@mcap/core accepted {path}"
    return done.stderr
