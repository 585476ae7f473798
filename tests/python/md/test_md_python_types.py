"""Behaviour of the generated Python types: numpy views, str fields, dynamic fields, dicts."""

from __future__ import annotations

import ctypes
import gc
from pathlib import Path
from types import ModuleType

import numpy as np
import pytest
from gen_modules import load_module

from ln_generate.cli import main

NAMES = ["robot/joint_state", "robot/tool_state", "robot/set_gains", "robot/plan_path",
         "robot/fault_event", "t/chars"]


@pytest.fixture(scope="module")
def m(tmp_path_factory: pytest.TempPathFactory) -> ModuleType:
    root = tmp_path_factory.mktemp("pytypes")
    (root / "md" / "t").mkdir(parents=True)
    (root / "md" / "t" / "chars").write_text("char label[8]\nchar initial\nint16_t ids[3]\n")
    out = root / "gen_pytypes.py"
    assert main(["-o", str(out), "--md-dir", str(root / "md"), *NAMES]) == 0
    return load_module("gen_pytypes", out, register=True)


def test_array_fields_are_writable_views(m: ModuleType) -> None:
    js = m.robot_joint_state_t()
    view = js.position
    assert isinstance(view, np.ndarray) and view.dtype == np.dtype("<f8") and view.shape == (7,)
    view[:] = np.arange(7) * 0.5
    js.velocity = [1, 2, 3, 4, 5, 6, 7]
    raw = bytes(js)
    assert np.frombuffer(raw, "<f8", 7, 12).tolist() == [0, 0.5, 1, 1.5, 2, 2.5, 3]
    assert np.frombuffer(raw, "<f8", 7, 68).tolist() == [1, 2, 3, 4, 5, 6, 7]
    with pytest.raises(ValueError):
        js.effort = [1, 2, 3]


def test_views_of_a_buffer_share_its_memory(m: ModuleType) -> None:
    buf = bytearray(m.robot_joint_state_t.SIZE)
    js = m.robot_joint_state_t.from_buffer(buf)
    js.position[6] = 42.0
    js.cycle = 7
    assert np.frombuffer(bytes(buf), "<f8", 1, 12 + 6 * 8)[0] == 42.0
    assert int.from_bytes(buf[8:12], "little") == 7


def test_nested_struct_and_nested_array(m: ModuleType) -> None:
    ts = m.robot_tool_state_t.from_dict(
        {"flange": {"position": [1, 2, 3]}, "stiffness": list(range(36)), "gripper_closed": 1}
    )
    ts.tool.orientation[3] = 1.0
    d = ts.to_dict()
    assert d["flange"]["position"] == [1, 2, 3]
    assert d["tool"]["orientation"] == [0, 0, 0, 1]
    assert d["stiffness"][35] == 35
    assert m.robot_tool_state_t.from_dict(d).to_dict() == d


def test_char_fields_are_str(m: ModuleType) -> None:
    c = m.t_chars_t()
    c.label = "gripper"
    assert c.label == "gripper"
    assert bytes(c)[:8] == b"gripper\0"
    c.label = b"12345678"  # exactly full: no terminator needed
    assert c.label == "12345678"
    with pytest.raises(ValueError, match="do not fit in char\\[8\\]"):
        c.label = "123456789"
    c.initial = b"Z"
    assert c.to_dict() == {"label": "12345678", "initial": "Z", "ids": [0, 0, 0]}


def test_dynamic_fields_accept_lists_arrays_bytes_and_str(m: ModuleType) -> None:
    sg = m.robot_set_gains_t()
    sg.req.profile_name = "soft"
    gc.collect()
    assert sg.req.profile_name_len == 4 and sg.req.profile_name == "soft"
    sg.resp.message = b"bad \xff bytes"
    assert sg.resp.message == "bad \udcff bytes"  # lossless round trip of non-UTF-8
    assert m.robot_set_gains_t.from_dict(sg.to_dict()).resp.message == sg.resp.message
    pp = m.robot_plan_path_t()
    pp.req.constraints = [{"data": "joint_limits"}, {"data": "collision"}]
    pp.resp.waypoints = [m.robot_joint_state_t.from_dict({"cycle": 1}), {"cycle": 2}]
    gc.collect()
    assert [c.data for c in pp.req.constraints] == ["joint_limits", "collision"]
    assert [w.cycle for w in pp.resp.waypoints] == [1, 2]
    assert pp.resp.waypoints_len == 2


def test_dynamic_numeric_field(tmp_path: Path) -> None:
    (tmp_path / "t").mkdir()
    (tmp_path / "t" / "dyn").write_text("float* samples\n")
    out = tmp_path / "gen_dyn.py"
    assert main(["-o", str(out), "--md-dir", str(tmp_path), "t/dyn"]) == 0
    ns: dict[str, object] = {}
    exec(compile(out.read_text(), str(out), "exec"), ns)
    cls = ns["t_dyn_t"]
    obj = cls()  # type: ignore[operator]
    assert obj.samples.shape == (0,)
    obj.samples = np.array([1.5, 2.5, 3.5])
    gc.collect()
    assert obj.samples.dtype == np.dtype("<f4") and obj.samples.tolist() == [1.5, 2.5, 3.5]
    with pytest.raises(ValueError, match="1-d"):
        obj.samples = [[1, 2], [3, 4]]
    obj2 = cls()  # type: ignore[operator]
    obj2.samples_len = 2  # length without a buffer: refused instead of reading garbage
    with pytest.raises(ValueError, match="NULL pointer"):
        _ = obj2.samples


def test_from_dict_rejects_unknown_fields(m: ModuleType) -> None:
    with pytest.raises(KeyError, match="robot/joint_state: no field 'positon'"):
        m.robot_joint_state_t.from_dict({"positon": [0] * 7})


def test_constants_and_registry(m: ModuleType) -> None:
    js = m.robot_joint_state_t
    assert ctypes.sizeof(js) == js.SIZE == 180
    assert js.SIGNATURE == "double 8 1,uint32_t 4 1,double 8 7,double 8 7,double 8 7"
    assert m.MESSAGES["robot/set_gains"] is m.robot_set_gains_t
    assert m.robot_set_gains_t.KIND == "service"
    assert m.robot_fault_event_t.from_dict({"call": {"text": "hot"}}).call.text == "hot"


def test_own_dynamic_data_detaches_from_foreign_memory(m: ModuleType) -> None:
    """A struct that C code pointed at its own memory (as libln does with responses) owns
    copies after own_dynamic_data, at every depth: changing the original changes nothing."""
    from links_and_nodes.md_types import own_dynamic_data

    source = m.robot_plan_path_t()
    source.req.constraints = [{"data": "joint_limits"}, {"data": "collision"}]
    source.resp.waypoints = [{"cycle": 1}, {"cycle": 2}]
    source.resp.message = "done"
    copy = m.robot_plan_path_t.from_buffer_copy(bytes(source))  # same pointers
    own_dynamic_data(copy)
    first = source.req.constraints[0]
    ctypes.memset(type(first)._ln_raw_fields_["data"].__get__(first), ord("X"), 12)
    source.req.constraints[1].data_len = 0
    source.resp.waypoints[1].cycle = 99
    del source
    gc.collect()
    assert copy.to_dict()["req"]["constraints"] == [{"data": "joint_limits"},
                                                    {"data": "collision"}]
    assert [w.cycle for w in copy.resp.waypoints] == [1, 2] and copy.resp.message == "done"
    empty = m.robot_plan_path_t()
    own_dynamic_data(empty)  # length 0 stays a NULL pointer
    assert empty.to_dict()["resp"] == {"waypoints": [], "status": 0, "message": ""}


def test_dynamic_values_keep_their_buffer(tmp_path: Path) -> None:
    """What a dynamic field gave out stays valid when the field gets a new value."""
    (tmp_path / "t").mkdir()
    (tmp_path / "t" / "dyn").write_text("double* values\n")
    out = tmp_path / "gen_dyn2.py"
    assert main(["-o", str(out), "--md-dir", str(tmp_path), "t/dyn"]) == 0
    ns: dict[str, object] = {}
    exec(compile(out.read_text(), str(out), "exec"), ns)
    obj = ns["t_dyn_t"]()  # type: ignore[operator]
    obj.values = [1.0, 2.0, 3.0]
    old = obj.values
    obj.values = [4.0]
    gc.collect()
    assert isinstance(old.base, ctypes.Array)  # the buffer itself, not the struct
    assert old.tolist() == [1.0, 2.0, 3.0] and obj.values.tolist() == [4.0]


def _spoil(struct: object, field: str) -> None:
    """Overwrite what dynamic char field `field` of `struct` points to, in place."""
    ptr = type(struct)._ln_raw_fields_[field].__get__(struct)
    ctypes.memset(ptr, ord("X"), getattr(struct, f"{field}_len"))


def test_structs_given_to_fields_hand_over_a_copy_of_their_dynamic_data() -> None:
    import links_and_nodes as ln

    req_cls = dict((n, e) for n, _k, e, _c in ln.message_class("robot/plan_path")._ln_specs_)["req"]
    nested = dict((n, e) for n, _k, e, _c in req_cls._ln_specs_)["constraints"]
    # the nested class of plan_path, and the class ln.message_class gives for ln/string
    items = [nested.from_dict({"data": "joint_limits"}),
             ln.message_class("ln/string").from_dict({"data": "collision"})]
    req = req_cls()
    req.constraints = items
    for item in items:
        _spoil(item, "data")
    assert [c.data for c in req.constraints] == ["joint_limits", "collision"]


@pytest.mark.parametrize("how", ["attribute", "update"])
def test_nested_structs_hand_over_a_copy_of_their_dynamic_data(tmp_path: Path, how: str) -> None:
    (tmp_path / "t").mkdir()
    (tmp_path / "t" / "leaf").write_text("char* text\n")
    (tmp_path / "t" / "tree").write_text('define leaf as "t/leaf"\nleaf one\nleaf two[2]\n')
    out = tmp_path / "gen_tree.py"
    assert main(["-o", str(out), "--md-dir", str(tmp_path), "t/tree"]) == 0
    mod = load_module(f"gen_tree_{how}", out)
    tree = mod.t_tree_t()
    leaf_cls = type(tree.one)
    one = leaf_cls.from_dict({"text": "one"})
    two = [leaf_cls.from_dict({"text": f"two{i}"}) for i in range(2)]
    if how == "attribute":
        tree.one = one
        tree.update({"two": two})
    else:
        tree.update({"one": one, "two": two})
    for leaf in (one, *two):
        _spoil(leaf, "text")
    del one, two, leaf
    gc.collect()
    assert tree.to_dict() == {"one": {"text": "one"}, "two": [{"text": "two0"}, {"text": "two1"}]}


def test_char_fields_refuse_what_is_not_text(m: ModuleType) -> None:
    gains = m.robot_set_gains_request_t()
    chars = m.t_chars_t()
    for value in (5, [104, 105], None, 2.5):
        with pytest.raises(TypeError, match="str or bytes"):
            gains.profile_name = value  # char*: bytes(5) used to make five NULs
        with pytest.raises(TypeError, match="str or bytes"):
            chars.label = value  # char[8]
    gains.profile_name = bytearray(b"soft")
    chars.label = memoryview(b"arm")
    assert (gains.profile_name, chars.label) == ("soft", "arm")
    chars.initial = 65  # a single char still takes its code
    assert chars.initial == "A"
