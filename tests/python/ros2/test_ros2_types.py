"""The ROS 2 names, the ros2msg schema and the RIHS01 hash: known ROS 2 types against their
published hashes, md types against rosbags' own RIHS01, and what is refused."""

from __future__ import annotations

import re

import pytest
from ros2_samples import REPO, TEST_MDS, md_names, real_topic_mds, rosbags_store, topic_mds

from links_and_nodes import ros2
from links_and_nodes.ros2 import RosField, RosType, hash_types
from links_and_nodes.ros2.names import field_names

PACKAGE = re.compile(r"^(?!.*__)(?!.*_$)[a-z][a-z0-9_]*$")
TYPE = re.compile(r"^[A-Z][A-Za-z0-9]*$")
FIELD = PACKAGE

TIME = RosType("builtin_interfaces/msg/Time",
               (RosField("sec", "int32"), RosField("nanosec", "uint32")))
# The hashes rosidl writes for these types (type_hashes in share/<pkg>/msg/<Type>.json of
# ROS 2 Jazzy; the same values rmw_zenoh puts in its keys).
KNOWN = [
    ([RosType("std_msgs/msg/String", (RosField("data", "string"),))],
     "RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18"),
    ([RosType("geometry_msgs/msg/Point", tuple(RosField(n, "float64") for n in "xyz"))],
     "RIHS01_6963084842a9b04494d6b2941d11444708d892da2f4b09843b9c43f42a7f6881"),
    ([TIME], "RIHS01_b106235e25a4c5ed35098aa0a61a3ee9c9b18d197f398b0e4206cea9acf9c197"),
    ([RosType("std_msgs/msg/Header", (RosField("stamp", "builtin_interfaces/msg/Time"),
                                      RosField("frame_id", "string"))), TIME],
     "RIHS01_f49fb3ae2cf070f793645ff749683ac6b06203e41c891e17701b1cb597ce6a01"),
]


@pytest.mark.parametrize(("types", "expected"), KNOWN, ids=[t[0].name for t, _ in KNOWN])
def test_known_ros2_types_hash_as_published(types: list[RosType], expected: str) -> None:
    assert hash_types(types) == expected


def test_rosbags_agrees_on_known_and_unusual_types() -> None:
    odd = RosType("x_pkg/msg/Odd", (RosField("s", "string", 0, 9), RosField("a", "int16", 4),
                                    RosField("t", "builtin_interfaces/msg/Time", 2)))
    empty = RosType("x_pkg/msg/Empty", ())  # ROS adds a placeholder uint8 member
    for types in [*(t for t, _ in KNOWN), [odd, TIME], [empty]]:
        schema = "".join([types[0].msg_text(), *(
            f"{'=' * 80}\nMSG: {t.name}\n{t.msg_text()}" for t in types[1:])])
        store = rosbags_store(schema, types[0].name)
        assert store.hash_rihs01(types[0].name) == hash_types(types)


CASES = ([(str(REPO / "message_definitions"), n)
          for n in topic_mds(REPO / "message_definitions")]
         + [(str(TEST_MDS), n) for n in topic_mds(TEST_MDS)] + real_topic_mds())


@pytest.mark.parametrize(("md_dir", "md_name"), CASES, ids=[f"{d.split('/')[-1]}:{n}"
                                                           for d, n in CASES])
def test_md_types_hash_as_rosbags_hashes_their_schema(md_dir: str, md_name: str) -> None:
    c = ros2.codec(md_name, [md_dir])
    h = ros2.rihs01(md_name, [md_dir])
    assert re.fullmatch(r"RIHS01_[0-9a-f]{64}", h)
    assert rosbags_store(c.schema_text, c.type_name).hash_rihs01(c.type_name) == h
    desc = ros2.type_description(md_name, [md_dir])
    assert desc["type_description"]["type_name"] == c.type_name
    names = [c.type_name] + [t["type_name"] for t in desc["referenced_type_descriptions"]]
    for name in names:
        package, msg, typ = name.split("/")
        assert PACKAGE.match(package) and msg == "msg" and TYPE.match(typ), name
    for t in [desc["type_description"], *desc["referenced_type_descriptions"]]:
        for f in t["fields"]:
            assert FIELD.match(f["name"]), f["name"]


def test_schema_has_each_nested_type_once() -> None:
    text = ros2.msg_schema("ros2test/assembly", [str(TEST_MDS)])
    assert text == (
        "uint8 kind\nros2test/Part[3] parts\nrobot/Pose where\nstring<=7 note\nint16 tail\n"
        f"{'=' * 80}\nMSG: ros2test/Part\nstring<=5 tag\nfloat64 weight\nuint8[3] flags\n"
        f"{'=' * 80}\nMSG: robot/Pose\nfloat64[3] position\nfloat64[4] orientation\n")


def test_primitive_mapping() -> None:
    text = ros2.msg_schema("ros2test/all_types", [str(TEST_MDS)])
    assert text.splitlines() == [
        "int8 i8", "uint8 u8", "int16 i16", "uint16 u16", "int32 i32", "uint32 u32",
        "int64 i64", "uint64 u64", "float32 f32", "float64 f64", "uint8 letter",
        "string<=16 label", "float64 after_label", "string<=3 code", "uint16[3] odd",
        "float32[5] values", "int64[2] big"]


@pytest.mark.parametrize(("md_name", "ros"), [
    ("robot/joint_state", "robot/msg/JointState"),
    ("time", "ln/msg/Time"),
    ("a/b/c_d", "a_b/msg/CD"),
    ("RobotKernel/Sub-Dir/jointState", "robot_kernel_sub_dir/msg/JointState"),
    ("x/2fast", "x/msg/M2fast"),
    ("9lives/x", "ln_9lives/msg/X"),
    ("__/___", "ln/msg/Msg"),
])
def test_type_names(md_name: str, ros: str) -> None:
    assert ros2.ros2_type_name(md_name) == ros


def test_field_names() -> None:
    assert field_names(["Position", "jointPos", "joint_pos", "HTTPServer", "X", "_x_", "a__b",
                        "9x", "_"]) == [
        "position", "joint_pos", "joint_pos_2", "http_server", "x", "x_2", "a_b", "f_9x",
        "field"]
    assert ros2.msg_schema("ros2test/Mixed_Names", [str(TEST_MDS)]).splitlines() == [
        "float64 position", "uint32 joint_pos", "uint32 joint_pos_2", "uint8 http_server",
        "float32 x"]
    assert ros2.ros2_type_name("ros2test/Mixed_Names") == "ros2test/msg/MixedNames"


def test_dynamic_fields_services_and_events_are_refused() -> None:
    with pytest.raises(ros2.CdrError, match=r"md 'ros2test/with_dynamic': field 'parts' is "
                                            r"dynamic \(ros2test/part\* parts\)"):
        ros2.codec("ros2test/with_dynamic", [str(TEST_MDS)])
    with pytest.raises(ValueError, match=r"md 'ln/string': field 'data' is dynamic"):
        ros2.rihs01("ln/string")
    with pytest.raises(ros2.CdrError, match="md 'robot/set_gains' is a service"):
        ros2.msg_schema("robot/set_gains")
    with pytest.raises(ros2.CdrError, match="md 'robot/fault_event' is an event"):
        ros2.codec("robot/fault_event")


def test_every_repo_md_maps_or_is_refused_by_name() -> None:
    root = REPO / "message_definitions"
    topics = set(topic_mds(root))
    for name in md_names(root):
        if name in topics:
            assert ros2.codec(name, [str(root)]).type_name == ros2.ros2_type_name(name)
        else:
            with pytest.raises(ros2.CdrError, match=f"md '{name}'"):
                ros2.codec(name, [str(root)])
