"""The Python parameter block (`clnt.get_parameter_block`, `ln.parameter_block`): parameters
of every kind with inputs and defaults, a Python validator that may refuse with a reason (or
fail), update() from the program's loop, changed flags, and the block going away with its
client or by close()."""

from __future__ import annotations

import threading

import numpy as np
import pytest
from polling import wait_for

import links_and_nodes as ln
from links_and_nodes.tools.scripting import ManagerError

from .conftest import Lab


class Loop:
    """update() in a thread, as a program's loop would; records the changes it saw."""

    def __init__(self, blk: ln.parameter_block) -> None:
        self.blk = blk
        self.stop = threading.Event()
        self.changes: list[list[str]] = []
        self.errors: list[BaseException] = []
        self.thread = threading.Thread(target=self.run, name="param-loop")
        self.thread.start()

    def run(self) -> None:
        try:
            while not self.stop.is_set():
                if self.blk.update() > 0:
                    self.changes.append(self.blk.changed())
                self.stop.wait(0.001)
        except BaseException as exc:  # noqa: BLE001 - reported by the test
            self.errors.append(exc)

    def end(self) -> None:
        self.stop.set()
        self.thread.join(30)
        assert not self.errors, self.errors


def plain(values: dict[str, object]) -> dict[str, object]:
    return {k: v.tolist() if isinstance(v, np.ndarray) else v for k, v in values.items()}


def make_block(clnt: ln.client) -> ln.parameter_block:
    blk = clnt.get_parameter_block("py")
    blk.add("speed", "double", default=0.5, min=0, max=2, description="m/s", input=False)
    blk.add("offsets", "float", 3, default=[0.25, 0.5, 0.75])
    blk.add("steps", "int16_t", 2, default=[1, 2], min=-10, max=10)
    blk.add("name", "char", 8, default="robot", input=False)
    blk.add("serial", "uint64_t", default=2**63 + 5, read_only=True, input=False)

    def validate(name: str, value: object) -> object:
        if name == "steps" and isinstance(value, np.ndarray) and value[0] == value[1]:
            return "the two steps must differ"
        if name == "name" and value == "crash":
            raise RuntimeError("no crashing")
        if name == "speed" and value == 1.5:
            return False
        return None

    blk.set_validator(validate)
    blk.register()
    return blk


def test_python_block_through_the_tools(lab: Lab) -> None:
    with ln.client("pyctl", lab.address) as clnt:
        blk = make_block(clnt)
        assert blk.service_name == "pyctl.parameters.py"
        p = blk.parameters["offsets"]
        assert blk.update() == 0
        assert plain(blk.values()) == {"speed": 0.5, "offsets": [0.25, 0.5, 0.75],
                                       "steps": [1, 2], "name": "robot", "serial": 2**63 + 5}
        p.input = [1, 2, 3]  # the program's input reaches the value at the next update
        assert list(p.value) == [0.25, 0.5, 0.75]
        blk.update()
        assert list(p.value) == [1.0, 2.0, 3.0]
        loop = Loop(blk)
        try:
            s = lab.script()
            assert s.param_blocks() == ["pyctl.py"]
            s.param_set("py", {"speed": 1, "steps": [3, -3], "name": "arm"})
            wait_for(lambda: loop.changes, "the change in the loop")
            assert loop.changes == [["speed", "steps", "name"]]
            assert blk["speed"] == 1.0 and list(blk["steps"]) == [3, -3]
            assert blk["name"] == "arm"
            assert s.param_get("py", "serial") == 2**63 + 5
            for name, value, text in [
                    ("steps", [4, 4], "steps: the two steps must differ"),
                    ("name", "crash", "name: RuntimeError: no crashing"),
                    ("speed", 1.5, "speed: refused by the validator"),
                    ("speed", 3, "speed: 3 is above the maximum 2"),
                    ("steps", [1, 11], "steps[1]: 11 is above the maximum 10"),
                    ("serial", 1, "serial is read-only"),
                    ("name", "too long!", "9 bytes does not fit in char[8]")]:
                with pytest.raises(ManagerError) as err:
                    s.param_set("py", name, value)
                assert text in str(err.value), (name, value)
            assert s.param_get("py") == {"speed": 1.0, "offsets": [1.0, 2.0, 3.0],
                                         "steps": [3, -3], "name": "arm",
                                         "serial": 2**63 + 5}
            assert s.param_reset("py") == ["speed", "steps", "name"]
            wait_for(lambda: len(loop.changes) == 2, "the reset in the loop")
            assert blk["speed"] == 0.5 and blk["name"] == "robot"
        finally:
            loop.end()
        blk.close()  # its service goes
        s2 = lab.script()
        wait_for(lambda: s2.param_blocks() == [], "the block's service gone")
        with pytest.raises(ValueError, match="closed"):
            blk.update()


def test_block_goes_with_its_client(lab: Lab) -> None:
    clnt = ln.client("pyctl2", lab.address)
    blk = make_block(clnt)
    s = lab.script()
    assert s.param_blocks() == ["pyctl2.py"]
    clnt.close()
    with pytest.raises(ValueError):
        blk.update()
    wait_for(lambda: s.param_blocks() == [], "the block's service gone with the client")


def test_bad_declarations(lab: Lab) -> None:
    with ln.client("pyctl3", lab.address) as clnt:
        blk = ln.parameter_block(clnt, "b")
        with pytest.raises(ValueError, match="not an md primitive"):
            blk.add("x", "bool")
        with pytest.raises(ValueError, match="expected 3 values"):
            blk.add("x", "double", 3, default=[1, 2])
        blk.add("x", "double")
        with pytest.raises(ln.LnExistError):
            blk.add("x", "double")
        with pytest.raises(ln.LnInvalError, match="must be 1..63 bytes"):
            blk.add("bad name", "double")
        with pytest.raises(ln.LnInvalError):
            ln.parameter_block(clnt, "a.b")  # a block name has no dots
        blk.register()
        with pytest.raises(ln.LnBusyError):
            blk.add("y", "double")
