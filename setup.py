"""What pyproject.toml cannot say: a wheel built by build_backend/links_and_nodes_build.py
carries the native parts of $LN_NATIVE_BUILD_DIR (a SCons variant directory) in the package
(lib/, bin/, include/: python/links_and_nodes/bundled.py finds them) and uPlot in the web UI's
static/vendor (with dagre, the graph view's layout), and is tagged for the platform
(py3-none: ctypes, no Python ABI); an sdist carries them too, so installing it needs no npm.  Without $LN_NATIVE_BUILD_DIR (editable
installs) the build is Python-only."""

import atexit
import os
import shutil
import tempfile
from pathlib import Path

from setuptools import Distribution, setup
from setuptools.command.bdist_wheel import bdist_wheel
from setuptools.command.build_py import build_py
from setuptools.command.sdist import sdist

HERE = Path(__file__).resolve().parent
NATIVE_DIR = os.environ.get("LN_NATIVE_BUILD_DIR")
VENDOR = "python/links_and_nodes/manager/frontends/webui/static/vendor"
UPLOT = ["uPlot.iife.min.js", "uPlot.min.css", "LICENSE"]
DAGRE = ["dagre.min.js", "dagre.LICENSE"]
# (from, to): from the variant directory (or the source tree, "#..."), to the package
NATIVE = [("libln/libln.so.1.0.0", "lib/libln.so.1"),
          ("libln_pull/libln_pull.so.1.0.0", "lib/libln_pull.so.1"),
          ("libln/links_and_nodes/libln_admin.so", "lib/links_and_nodes/libln_admin.so"),
          ("ln_daemon/ln_daemon", "bin/ln_daemon")]
HEADERS = ["libln/include/ln/ln.h", "libln/include/ln/ln.hpp",
           "libln/include/ln/parameters.hpp", "libln/include/ln/waitset.hpp",
           "libln_pull/include/ln/ndn.h", "libln_pull/include/ln/pull.h",
           "libln_pull/include/ln/pull_udp.h"]


def uplot_dir() -> Path:
    """uPlot: in an unpacked sdist already in static/vendor, in a checkout in build/webui."""
    for d in (HERE / VENDOR, HERE / "build" / "webui" / "uplot"):
        if all((d / f).is_file() for f in UPLOT):
            return d
    raise SystemExit("uPlot is missing: run `scons` (it fetches uPlot with npm into "
                     "build/webui/uplot)")


def dagre_dir() -> Path:
    """dagre: in an unpacked sdist already in static/vendor, in a checkout in build/webui."""
    for d in (HERE / VENDOR, HERE / "build" / "webui" / "dagre"):
        if all((d / f).is_file() for f in DAGRE):
            return d
    raise SystemExit("dagre is missing: run `scons` (it fetches dagre with npm into "
                     "build/webui/dagre)")


def copy_vendor(vendor: Path) -> None:
    """uPlot and dagre into a package's static/vendor."""
    vendor.mkdir(parents=True, exist_ok=True)
    for names, where in ((UPLOT, uplot_dir()), (DAGRE, dagre_dir())):
        for name in names:
            shutil.copy2(where / name, vendor / name)


class BuildPy(build_py):
    def run(self) -> None:
        super().run()
        if NATIVE_DIR and not getattr(self, "editable_mode", False):
            self._add_native(Path(self.build_lib) / "links_and_nodes")

    def _add_native(self, package: Path) -> None:
        for source, dest in NATIVE:
            target = package / dest
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(Path(NATIVE_DIR) / source, target)
        include = package / "include" / "ln"
        include.mkdir(parents=True, exist_ok=True)
        for header in HEADERS:
            shutil.copy2(HERE / header, include)
        copy_vendor(package / "manager" / "frontends" / "webui" / "static" / "vendor")


class Sdist(sdist):
    def make_release_tree(self, base_dir: str, files: list[str]) -> None:
        super().make_release_tree(base_dir, files)
        copy_vendor(Path(base_dir) / VENDOR)


class BdistWheel(bdist_wheel):
    def get_tag(self) -> tuple[str, str, str]:
        _, _, platform = super().get_tag()
        return ("py3", "none", platform) if NATIVE_DIR else ("py3", "none", "any")


class NativeDistribution(Distribution):
    def has_ext_modules(self) -> bool:
        return bool(NATIVE_DIR)


# setuptools' build/ would share the SCons tree's build/: a private one per run instead.
build_base = tempfile.mkdtemp(prefix="ln-setuptools-")
atexit.register(shutil.rmtree, build_base, ignore_errors=True)
setup(cmdclass={"build_py": BuildPy, "sdist": Sdist, "bdist_wheel": BdistWheel},
      distclass=NativeDistribution, options={"build": {"build_base": build_base}})
