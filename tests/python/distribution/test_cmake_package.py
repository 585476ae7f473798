"""The CMake package (cmake/, docs/install.md "CMake"): `scons install` into a private prefix,
then examples/cmake configures and builds against it with plain cmake, and its controller
exchanges robot/joint_state samples with Python through a manager; ln_generate_messages()
generates its header at build time and again, only then, when the md changes.  Needs cmake
(scripts/setup installs it; missing_test_tool); not run in the Debian package build, whose
tests/installed/run builds the example against the installed libln-dev instead."""

from __future__ import annotations

import fcntl
import os
import re
import shutil
import subprocess
import sys
import uuid
from collections.abc import Iterator
from pathlib import Path

import pytest
from buildtree import REPO, missing_test_tool

import links_and_nodes as ln
from links_and_nodes.manager.frontends import launch

pytestmark = pytest.mark.skipif(bool(os.environ.get("LN_PACKAGE_TESTS")),
                                reason="the package build's tests/installed/run covers it")

SAMPLES = 50
LIMIT = 300  # seconds: an upper bound for one build step, not a measurement


def run(*command: str | Path, cwd: Path | None = None) -> str:
    out = subprocess.run([str(c) for c in command], cwd=cwd, capture_output=True, text=True,
                         timeout=LIMIT, env={**os.environ, "PYTHONDONTWRITEBYTECODE": "1"})
    assert out.returncode == 0, f"{' '.join(map(str, command))}:\n{out.stdout}\n{out.stderr}"
    return out.stdout


@pytest.fixture(scope="module")
def prefix(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Path]:
    """A `scons install` of the checkout's release build into a private PREFIX.  Workers
    take turns (a lock file): two SCons runs in one tree would race on its database."""
    if shutil.which("cmake") is None:
        missing_test_tool("cmake")
    scons = Path(sys.executable).with_name("scons")
    root = tmp_path_factory.mktemp("cmake_prefix") / "prefix"
    lock = REPO / "build" / ".cmake-package-test.lock"
    lock.parent.mkdir(exist_ok=True)
    with open(lock, "w") as held:
        fcntl.flock(held, fcntl.LOCK_EX)
        run(scons if scons.exists() else "scons", "-Q", "-j2", "install", f"PREFIX={root}",
            "zenoh_core=no", "rust=no", cwd=REPO)
    yield root


def configure_and_build(source: Path, build: Path, prefix: Path) -> str:
    run("cmake", "-S", source, "-B", build, f"-DCMAKE_PREFIX_PATH={prefix}",
        "-DCMAKE_BUILD_TYPE=Release")
    return run("cmake", "--build", build)


def test_installed_package_files(prefix: Path) -> None:
    config = prefix / "lib" / "cmake" / "links_and_nodes"
    assert sorted(p.name for p in config.iterdir()) == [
        "links_and_nodesConfig.cmake", "links_and_nodesConfigVersion.cmake"]
    # Relocatable: no path of the installation is written into them.
    for path in config.iterdir():
        assert str(prefix) not in path.read_text(), path
    assert f'set(PACKAGE_VERSION "{ln.__version__}")' in \
        (config / "links_and_nodesConfigVersion.cmake").read_text()


def test_example_controller_talks_to_python(prefix: Path, tmp_path: Path) -> None:
    build = tmp_path / "build"
    configure_and_build(REPO / "examples" / "cmake", build, prefix)
    header = build / "ln_generated" / "controller" / "controller_messages.hpp"
    assert "robot::joint_state_t" in header.read_text()
    controller = build / "controller"
    # The imported target links the prefix's libln (the build tree's RPATH points there).
    libs = run("ldd", controller)
    assert re.search(rf"libln\.so\.1 => {re.escape(str(prefix))}/lib/libln\.so\.1 ", libs), libs

    topic = f"cmake_{uuid.uuid4().hex[:10]}"
    manager = launch.start_manager(f"cmake_{uuid.uuid4().hex[:12]}", tmp_path / "run",
                                   tmp_path / "manager.log")
    try:
        clnt = ln.client("cmake_test", manager.address)
        sub = clnt.subscribe(f"{topic}.state", "robot/joint_state", buffers=SAMPLES + 8)
        pub = clnt.publish(f"{topic}.reference", "robot/joint_state")
        pub.packet.cycle = 4242
        for j in range(7):
            pub.packet.position[j] = 0.25 * (j + 1)
        proc = subprocess.Popen([str(controller), topic, str(SAMPLES)], env=manager.env,
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        seen: list[int] = []
        try:
            # Samples of the state, in order, with the values the controller wrote; the
            # reference is written again every round, so it is there whenever it reads.
            while proc.poll() is None or len(seen) < SAMPLES:
                pub.write()
                pkt = sub.read(timeout=0.05)
                if pkt is None:
                    if proc.poll() is not None and len(seen) < SAMPLES:
                        break
                    continue
                cycle = int(pkt.cycle)
                assert list(pkt.position) == [cycle * (j + 1) / 1000.0 for j in range(7)]
                assert list(pkt.velocity) == [-cycle * (j + 1) / 1000.0 for j in range(7)]
                assert float(pkt.timestamp) == cycle * 0.01
                seen.append(cycle)
            out, err = proc.communicate(timeout=LIMIT)
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait()
        clnt.close()
    finally:
        assert manager.stop() == 0
    assert proc.returncode == 0, f"{out}\n{err}"
    assert seen == list(range(1, SAMPLES + 1))
    assert "controller: reference cycle 4242 position 0.25 0.5 0.75 1 1.25 1.5 1.75" in out


PROBE_C = """/* probe.c: prints the size and signature of the generated cmake_probe/sample. */
#include <stdio.h>

#include "probe_messages.h"

int main(void)
{
    printf("%zu %s\\n", sizeof(cmake_probe_sample_t), CMAKE_PROBE_SAMPLE_SIGNATURE);
    return 0;
}
"""

PROBE_CMAKE = """cmake_minimum_required(VERSION 3.16)
project(ln_probe LANGUAGES C)
find_package(links_and_nodes REQUIRED)
add_executable(probe probe.c)
target_link_libraries(probe PRIVATE links_and_nodes::ln)
ln_generate_messages(TARGET probe MDS cmake_probe/sample MD_DIRS md)
"""


def test_md_change_regenerates_the_header(prefix: Path, tmp_path: Path) -> None:
    source, build = tmp_path / "src", tmp_path / "build"
    md = source / "md" / "cmake_probe" / "sample"
    md.parent.mkdir(parents=True)
    md.write_text("uint32_t a\n")
    (source / "probe.c").write_text(PROBE_C)
    (source / "CMakeLists.txt").write_text(PROBE_CMAKE)
    configure_and_build(source, build, prefix)
    header = build / "ln_generated" / "probe" / "probe_messages.h"
    assert run(build / "probe").split(" ", 1)[0] == "4"

    # Nothing changed: the header is not generated again.
    before = header.stat().st_mtime_ns
    assert "ln_generate" not in run("cmake", "--build", build)
    assert header.stat().st_mtime_ns == before

    md.write_text("uint32_t a\ndouble b\n")
    if md.stat().st_mtime_ns <= before:  # a coarse file-system clock
        os.utime(md, ns=(before + 1_000_000_000, before + 1_000_000_000))
    assert "probe_messages.h" in run("cmake", "--build", build)
    assert header.stat().st_mtime_ns != before
    size, signature = run(build / "probe").strip().split(" ", 1)
    assert size == "12"
    assert "double" in signature


def test_unknown_md_fails_at_configure_time(prefix: Path, tmp_path: Path) -> None:
    source = tmp_path / "src"
    (source / "md").mkdir(parents=True)
    (source / "probe.c").write_text(PROBE_C)
    (source / "CMakeLists.txt").write_text(PROBE_CMAKE)
    out = subprocess.run(["cmake", "-S", str(source), "-B", str(tmp_path / "build"),
                          f"-DCMAKE_PREFIX_PATH={prefix}"], capture_output=True, text=True,
                         timeout=LIMIT)
    assert out.returncode != 0
    assert "ln_generate_messages(probe)" in out.stderr
    assert "cmake_probe/sample" in out.stderr


def test_moved_installation_is_found_where_it_is(prefix: Path, tmp_path: Path) -> None:
    moved = tmp_path / "moved"
    shutil.copytree(prefix, moved, symlinks=True)
    source = tmp_path / "src"
    source.mkdir()
    (source / "CMakeLists.txt").write_text(
        "cmake_minimum_required(VERSION 3.16)\nproject(where LANGUAGES NONE)\n"
        "find_package(links_and_nodes REQUIRED)\n"
        "get_target_property(lib links_and_nodes::ln IMPORTED_LOCATION)\n"
        "get_target_property(inc links_and_nodes::ln INTERFACE_INCLUDE_DIRECTORIES)\n"
        "get_target_property(pull links_and_nodes::ln_pull IMPORTED_LOCATION)\n"
        'message(STATUS "ln: ${lib} ${inc} ${pull} ${links_and_nodes_VERSION}")\n')
    out = run("cmake", "-S", source, "-B", tmp_path / "build", f"-DCMAKE_PREFIX_PATH={moved}")
    assert (f"-- ln: {moved}/lib/libln.so.1 {moved}/include {moved}/lib/libln_pull.so.1 "
            f"{ln.__version__}\n") in out
