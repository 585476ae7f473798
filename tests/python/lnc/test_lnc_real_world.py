"""The real `.lnc` files written for the original Links and Nodes (../shared/real_ln/lnc)
go through `ln_manager check`: an include file from a minimal main file with an instance
section, a main file as it is.  The outcome of every file is listed here: the ones that
fail with why, the warnings each gives, the `-D` stubs a few need.  Skipped without the
corpus only outside CI."""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

from links_and_nodes.manager.frontends import config_check as check

REPO = Path(__file__).resolve().parents[3]
CORPUS = REPO.parent / "shared" / "real_ln" / "lnc"
CORPUS_SIZE = 39

if not CORPUS.is_dir():
    if os.environ.get("CI"):
        pytest.fail(f"the real-world .lnc corpus {CORPUS} is missing (CI=1: this is a "
                    "failure)", pytrace=False)
    pytest.skip(f"the real-world .lnc corpus {CORPUS} is not here", allow_module_level=True)

FILES = sorted(str(p.relative_to(CORPUS)) for p in CORPUS.rglob("*.lnc*") if p.is_file())
MAIN_FILES = {"guide_dog_ln_runner/manager.lnc", "module_jitter_measurement/test.lnc"}

# File -> (why it cannot load here, the messages of its errors, after `file:line:col: `).
EXPECTED_FAILURES: dict[str, tuple[str, list[str]]] = {
    "guide_dog_ln_runner/manager.lnc": (
        "includes its author's /home/user/guide_dog/ln_runner/templates.inc.lnc, which "
        "defines the templates every process uses, and needs the environment of the tool "
        "that generated it (CISSYGEN)",
        ["environment variable 'CISSYGEN' is not set (a default is given as "
         "'%(env CISSYGEN, DEFAULT)')",
         "no file matches '/tmp/tmpln_ws/cissygen/**/*.lnc'",
         "included file '/home/user/guide_dog/ln_runner/templates.inc.lnc' not found",
         *[f"unknown template '{t}'" for t in (
             "pcvp_manager_gen", "yolov7_pcvp_gen", "pcvp_module_ln", "dense_pose_pcvp_gen",
             "pcvp_module_ln", "m3t_refiner_pcvp_gen", "pcvp_module_ln")]]),
    "robotkernel/generate_ln_includes_output.inc.lnc": (
        "includes three files of its author's install tree under /volume/software",
        [f"included file '/volume/software/robotkernel/packages/{pkg}/5/"
         f"${{DLRRM_HOST_PLATFORM}}/share/ln/{name}.inc.lnc' not found"
         for pkg, name in (("module_jitter_measurement", "module_jitter_measurement"),
                           ("module_posix_timer", "module_posix_timer"),
                           ("robotkernel", "robotkernel"))]),
}

_NO_MD = "message definition directory '{}' not found (ignored)"
_REAL_LN = CORPUS.parent
# File -> the warnings it gives (after `file:line:col: `); every other file gives none.
EXPECTED_WARNINGS: dict[str, list[str]] = {
    **{f: [_NO_MD.format(_REAL_LN / "share" / "message_definitions")] for f in (
        "module_ethercat/module_ethercat.inc.lnc", "module_pdrouting/module_pdrouting.inc.lnc",
        "service_provider_memory_inspection/interface_process_data_inspection.inc.lnc")},
    **{f: [_NO_MD.format(_REAL_LN / "share" / "ln" / "message_definitions")] for f in (
        "robotkernel/robotkernel.inc.lnc", "robotkernel/robotkernel_2015.inc.lnc",
        "service_provider_file_protocol/interface_file_protocol.inc.lnc",
        "service_provider_key_value/interface_key_value.inc.lnc",
        "service_provider_memory_inspection/interface_memory_inspection.inc.lnc",
        "service_provider_process_data_inspection/interface_process_data_inspection.inc.lnc",
        "service_provider_sercos_protocol/interface_sercos_protocol.inc.lnc")},
    # a real mistake in the branch for a local install, which the original never read
    "module_jitter_measurement/module_jitter_measurement.inc.lnc": [
        "unknown name '_base' in '%()' (in a branch that is not taken)"],
}


def _cissygen(tmp_path: Path) -> dict[str, str]:
    """What the build tool cissy generates beside test.lnc on its author's machine: a
    node map and the `robotkernel_gen` template (here: the smallest such files)."""
    gen = tmp_path / "cissygen"
    (gen / "robotkernel").mkdir(parents=True)
    (gen / "nodemap.inc.lnc").write_text("node_map\nrobot: localhost\n")
    (gen / "robotkernel" / "robotkernel_gen.lnc").write_text(
        "template robotkernel_gen\nnode: localhost\nready_regex: up and running\n")
    return {"CISSYGEN": str(gen)}


# File -> (why, the -D defines it gets).
STUBS = {
    "module_ethercat/module_ethercat.inc.lnc.in": (
        "uses module_ethercat_libpath without defining it (a mistake fixed in the "
        "generated .inc.lnc); an including file that defines it loads",
        lambda tmp_path: {"module_ethercat_libpath": "/opt/module_ethercat/lib"}),
    "module_jitter_measurement/test.lnc": (
        "includes what the build tool cissy generated on its author's machine, found "
        "through CISSYGEN", _cissygen),
}


def run_check(tmp_path: Path, rel: str, capsys: pytest.CaptureFixture[str],
              *extra: str) -> tuple[int, dict]:
    path = CORPUS / rel
    if rel in MAIN_FILES:
        main = path
    else:
        main = tmp_path / "main.lnc"
        main.write_text(f"instance\nname: real {rel}\nmanager: :54414\n\ninclude {path}\n")
    argv = [str(main), "--json", "--print", *extra]
    if rel in STUBS:
        for name, value in STUBS[rel][1](tmp_path).items():
            argv += ["-D", f"{name}={value}"]
    capsys.readouterr()
    status = check.main(argv)
    return status, json.loads(capsys.readouterr().out)


def test_the_corpus_is_complete() -> None:
    assert len(FILES) == CORPUS_SIZE, FILES
    assert set(EXPECTED_FAILURES) | set(EXPECTED_WARNINGS) | set(STUBS) <= set(FILES)
    assert len(FILES) - len(EXPECTED_FAILURES) >= 37


@pytest.mark.parametrize("rel", FILES)
def test_real_file(rel: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    status, result = run_check(tmp_path, rel, capsys)
    messages = [e["message"] for e in result["errors"]]
    if rel in EXPECTED_FAILURES:
        assert (status, result["ok"]) == (1, False)
        assert messages == EXPECTED_FAILURES[rel][1]
        return
    assert messages == []
    assert (status, result["ok"]) == (0, True)
    assert [w["message"] for w in result["warnings"]] == EXPECTED_WARNINGS.get(rel, [])
    for w in result["warnings"]:  # each at its place in that file
        assert w["file"] == str(CORPUS / rel) and w["line"] > 1 and w["col"] > 1
    # --strict: warnings fail the check
    if result["warnings"]:
        status, strict = run_check(tmp_path, rel, capsys, "--strict")
        assert (status, strict["ok"]) == (1, False)
        assert len(strict["errors"]) == len(result["warnings"])


def test_robotkernel_include_resolves_its_process(tmp_path: Path,
                                                  capsys: pytest.CaptureFixture[str]) -> None:
    """robotkernel.inc.lnc without customising defines: the process and its binary path
    for an rmpm release (no bin/robotkernel next to it), with the defaults of its ifndefs."""
    _, result = run_check(tmp_path, "robotkernel/robotkernel.inc.lnc", capsys)
    [proc] = result["processes"]
    assert proc["name"] == "robotkernel" and proc["node"] == "localhost"
    assert proc["command"].split() == [f"{_REAL_LN}/bin/$(ARCH)/robotkernel"]
    assert proc["depends_on"] == [] and proc["environment"] == {}


def test_robotkernel_include_with_its_defines(tmp_path: Path,
                                              capsys: pytest.CaptureFixture[str]) -> None:
    """The same file customised the way its header comment documents."""
    (tmp_path / "rk" / "bin").mkdir(parents=True)
    (tmp_path / "rk" / "bin" / "robotkernel").write_text("")
    rel = "robotkernel/robotkernel.inc.lnc"
    main = tmp_path / "main.lnc"
    main.write_text(f"instance\nname: rk\nmanager: :54414\ndefines\nrk_name: kernel_1\n"
                    f"rk_base: {tmp_path}/rk\nrk_debug: false\nrk_arguments: --config a.rkc\n"
                    f"rk_modules: /opt/modules\nrk_node: robot\n\ninclude {CORPUS / rel}\n")
    capsys.readouterr()
    assert check.main([str(main), "--json", "--print"]) == 0
    [proc] = json.loads(capsys.readouterr().out)["processes"]
    assert (proc["name"], proc["node"]) == ("kernel_1", "robot")
    assert proc["command"].split() == [f"{tmp_path}/rk/bin/robotkernel", "--config", "a.rkc"]
    assert proc["environment"] == {"ROBOTKERNEL_MODULE_PATH": "/opt/modules"}
