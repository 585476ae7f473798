"""The CDR codec of the ROS 2 mapping against two independent decoders (rosbags and
mcap-ros2-support): every topic md of message_definitions/, the test mds and the real mds
that fit topics; bit-exact round trips; precise errors for bad CDR."""

from __future__ import annotations

import os
import re
import struct

import numpy as np
import pytest
from ros2_samples import (
    REAL_MDS,
    REPO,
    TEST_MDS,
    differences,
    fill,
    ln_class,
    ln_values,
    mcap_decoder,
    plain,
    real_topic_mds,
    rosbags_store,
    same,
    topic_mds,
)

from links_and_nodes import ros2
from ln_generate import MdRegistry, default_md_dirs

CASES = ([(str(REPO / "message_definitions"), n)
          for n in topic_mds(REPO / "message_definitions")]
         + [(str(TEST_MDS), n) for n in topic_mds(TEST_MDS)] + real_topic_mds())
SAMPLES = 25


def _struct(md_dir: str, md_name: str):  # noqa: ANN202
    return MdRegistry(default_md_dirs([md_dir])).load(md_name).struct


def test_cases_cover_each_source() -> None:
    names = {n for _, n in CASES}
    assert {"robot/joint_state", "robot/tool_state", "ln/time", "ros2test/all_types",
            "ros2test/assembly"} <= names
    if not REAL_MDS.is_dir():  # the package build's copy of the tree has no corpus beside it
        if os.environ.get("CI"):
            pytest.fail(f"the real-world md corpus {REAL_MDS} is missing (CI=1: a failure)")
        pytest.skip(f"the real-world md corpus {REAL_MDS} is not here")
    assert len(real_topic_mds()) >= 5


@pytest.mark.parametrize(("md_dir", "md_name"), CASES, ids=[f"{d.split('/')[-1]}:{n}"
                                                           for d, n in CASES])
def test_values_equal_through_both_decoders(md_dir: str, md_name: str) -> None:
    c = ros2.codec(md_name, [md_dir])
    s = _struct(md_dir, md_name)
    cls = ln_class(md_name, [md_dir])
    store = rosbags_store(c.schema_text, c.type_name)
    mcap = mcap_decoder(c.schema_text, c.type_name)
    rng = np.random.default_rng(sum(md_name.encode()))
    for _ in range(SAMPLES):
        raw = fill(s, rng)
        cdr = c.encode(raw)
        assert cdr[:4] == b"\x00\x01\x00\x00"
        assert c.decode(cdr) == raw
        expected = ln_values(cls.from_buffer_copy(raw).to_dict(), s)
        by_rosbags = plain(store.deserialize_cdr(cdr, c.type_name))
        assert same(by_rosbags, expected), differences(by_rosbags, expected)
        by_mcap = plain(mcap(cdr))
        assert same(by_mcap, expected), differences(by_mcap, expected)


@pytest.mark.parametrize(("md_dir", "md_name"), CASES, ids=[f"{d.split('/')[-1]}:{n}"
                                                           for d, n in CASES])
def test_bytes_equal_what_rosbags_serializes(md_dir: str, md_name: str) -> None:
    c = ros2.codec(md_name, [md_dir])
    store = rosbags_store(c.schema_text, c.type_name)
    rng = np.random.default_rng(7)
    for _ in range(5):
        raw = fill(_struct(md_dir, md_name), rng, payloads=False)
        cdr = c.encode(raw)
        assert store.serialize_cdr(store.deserialize_cdr(cdr, c.type_name), c.type_name) == cdr


def test_nan_payloads_and_negative_zero_survive() -> None:
    c = ros2.codec("ros2test/all_types", [str(TEST_MDS)])
    cls = ln_class("ros2test/all_types", [str(TEST_MDS)])
    m = cls()
    m.label = "x"
    raw = bytearray(bytes(m))
    snan64 = b"\x01\x00\x00\x00\x00\x00\xf4\x7f"
    snan32 = b"\x01\x00\xa0\x7f"
    f64 = cls.f64.offset
    raw[f64:f64 + 8] = snan64
    raw[cls.f32.offset:cls.f32.offset + 4] = snan32
    raw[cls.after_label.offset:cls.after_label.offset + 8] = struct.pack("<d", -0.0)
    cdr = c.encode(bytes(raw))
    assert snan64 in cdr and snan32 in cdr
    assert c.decode(cdr) == bytes(raw)


def test_char_text_up_to_its_first_nul() -> None:
    c = ros2.codec("ros2test/all_types", [str(TEST_MDS)])
    cls = ln_class("ros2test/all_types", [str(TEST_MDS)])
    m = cls()
    m.label = "0123456789abcdef"  # all 16 bytes, no NUL in the ln field
    m.code = "é"
    cdr = c.encode(bytes(m))
    assert struct.pack("<I", 17) + b"0123456789abcdef\x00" in cdr
    assert struct.pack("<I", 3) + "é".encode() + b"\x00" in cdr
    assert c.decode(cdr) == bytes(m)


def _sample(md_name: str) -> tuple[ros2.CdrCodec, bytes]:
    c = ros2.codec(md_name, [str(TEST_MDS)])
    raw = fill(MdRegistry(default_md_dirs([str(TEST_MDS)])).load(md_name).struct,
               np.random.default_rng(3))
    return c, c.encode(raw)


@pytest.mark.parametrize("md_name", ["ros2test/all_types", "ros2test/assembly"])
def test_every_truncation_is_refused_with_its_offset(md_name: str) -> None:
    c, cdr = _sample(md_name)
    for cut in range(len(cdr)):
        with pytest.raises(ros2.CdrError, match=r"at byte (\d+)") as e:
            c.decode(cdr[:cut])
        offset = int(e.value.args[0].split("at byte ")[1].split(":")[0])
        assert offset <= cut
        assert md_name in str(e.value)
        if cut >= 4:
            assert "field '" in str(e.value), str(e.value)


def test_bad_cdr_names_field_and_offset() -> None:
    c = ros2.codec("ros2test/assembly", [str(TEST_MDS)])
    cls = ln_class("ros2test/assembly", [str(TEST_MDS)])
    m = cls()
    m.parts[1].tag = "abc"
    cdr = bytearray(c.encode(bytes(m)))
    at = cdr.index(struct.pack("<I", 4) + b"abc\x00")
    long = bytes(cdr[:at]) + struct.pack("<I", 7) + b"abcdef\x00" + bytes(cdr[at + 8:])
    with pytest.raises(ros2.CdrError, match=rf"at byte {at}: field 'parts\[1\]\.tag' is a "
                                            r"string of 6 bytes, longer than its char\[5\]"):
        c.decode(long)
    no_nul = bytearray(cdr)
    no_nul[at + 7] = ord("d")
    with pytest.raises(ros2.CdrError, match=rf"at byte {at + 7}: the string of field "
                                            r"'parts\[1\]\.tag' does not end with a NUL"):
        c.decode(bytes(no_nul))
    with pytest.raises(ros2.CdrError, match="at byte 0: encapsulation 00 00 is not"):
        c.decode(b"\x00\x00\x00\x00" + bytes(cdr[4:]))
    with pytest.raises(ros2.CdrError, match=rf"at byte {len(cdr)}: 4 bytes follow"):
        c.decode(bytes(cdr) + b"\x00" * 4)
    assert c.decode(bytes(cdr) + b"\x00" * 3) == bytes(m)  # DDS padding to 4 bytes
    with pytest.raises(ros2.CdrError, match="a sample is 114 bytes, not 113"):
        c.encode(bytes(113))


def test_codec_is_cached_and_describes_the_type() -> None:
    c = ros2.codec("robot/joint_state")
    assert ros2.codec("robot/joint_state") is c
    assert c.type_name == "robot/msg/JointState"
    assert c.message_size == 180
    assert c.schema_text == ros2.msg_schema("robot/joint_state")
    assert c.type_hash == ros2.rihs01("robot/joint_state")


def test_joint_state_layout_is_cdr() -> None:
    """timestamp at 0, cycle at 8, 4 bytes of padding, then the doubles at 16."""
    c = ros2.codec("robot/joint_state")
    raw = bytes(range(180))
    cdr = c.encode(raw)
    assert len(cdr) == 4 + 184
    assert cdr[4:16] == raw[:12] and cdr[16:20] == bytes(4) and cdr[20:] == raw[12:]


@pytest.mark.parametrize("md_name", ["ros2test/all_types", "ros2test/assembly"])
def test_corrupt_cdr_decodes_to_a_sample_or_cdr_error(md_name: str) -> None:
    c, cdr = _sample(md_name)
    rng = np.random.default_rng(11)
    refused = 0
    for _ in range(2000):
        data = bytearray(cdr)
        for _ in range(int(rng.integers(1, 4))):
            data[int(rng.integers(len(data)))] = int(rng.integers(256))
        data = data[:int(rng.integers(len(data) - 8, len(data) + 1))]
        try:
            assert len(c.decode(bytes(data))) == c.message_size
        except ros2.CdrError as e:
            assert re.search(r"at byte \d+: ", str(e)), str(e)
            refused += 1
    assert refused > 100  # the damage is often detectable: cut short, bad length, no NUL
