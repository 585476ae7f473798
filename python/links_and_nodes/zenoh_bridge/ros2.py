"""The optional ROS 2 mapping of ln_zenoh (`--ros2`, docs/zenoh.md "ROS 2"): outbound topics are
also published under rmw_zenoh's keys, as CDR (links_and_nodes.ros2: the md's ROS 2 type, its
RIHS01 hash) with rmw_zenoh's attachment, and announced with `@ros2_lv` liveliness tokens of a
node named after the instance.

    data key   <domain>/<topic, '.' -> '/'>/<pkg>::msg::dds_::<Type>_/RIHS01_<64 hex>
    token      @ros2_lv/<domain>/<zid>/0/<entity id>/MP/%/%/<node>/<%topic>/<type>/<hash>/<qos>
    attachment i64 seq, i64 publish time ns, 0x10, 16-byte GID (33 bytes, as zenoh-ext
               serializes rmw_zenoh's int64, int64, std::array<uint8_t, 16>)
"""

from __future__ import annotations

import hashlib
import re
import struct
import threading
from typing import Any

from ..ros2 import codec, dds_type_name, ros2_type_name

_ATT = struct.Struct("<qqB")
GID_SIZE = 16
ATTACHMENT_SIZE = _ATT.size + GID_SIZE  # 33
_NOT_ROS = re.compile(r"[^A-Za-z0-9_/]")


def ros_topic(name: str) -> str:
    """The ROS topic of an ln topic: '/' + name with '.' as '/', other characters not allowed
    in ROS names as '_'."""
    return "/" + _NOT_ROS.sub("_", name.replace(".", "/")).strip("/")


def ros_type(md_name: str) -> str:
    """`robot/joint_state` -> `robot::msg::dds_::JointState_` (links_and_nodes.ros2's naming)."""
    return dds_type_name(ros2_type_name(md_name))


def type_hash(md_name: str) -> str:
    """The RIHS01 hash of the md's ROS 2 type (CdrError for an md without one)."""
    return codec(md_name).type_hash


def data_key(domain: int, topic: str, md_name: str) -> str:
    return f"{domain}/{ros_topic(topic)[1:]}/{ros_type(md_name)}/{type_hash(md_name)}"


def mangle(name: str) -> str:
    return name.replace("/", "%")


def node_name(instance: str) -> str:
    return "ln_zenoh_" + re.sub(r"[^A-Za-z0-9_]", "_", instance)


def qos(depth: int) -> str:
    """rmw_zenoh's QoS part: reliability:durability:history,depth:deadline:lifespan:liveliness,
    empty meaning the default (reliable, volatile, keep last)."""
    return f"::,{depth}:,:,:,,"


def node_token(domain: int, zid: str, node: str) -> str:
    return f"@ros2_lv/{domain}/{zid}/0/0/NN/%/%/{node}"


def publisher_token(domain: int, zid: str, node: str, entity_id: int, topic: str,
                    md_name: str, depth: int) -> str:
    return (f"@ros2_lv/{domain}/{zid}/0/{entity_id}/MP/%/%/{node}/{mangle(ros_topic(topic))}/"
            f"{ros_type(md_name)}/{type_hash(md_name)}/{qos(depth)}")


def gid(token: str) -> bytes:
    """16 bytes naming a publisher: the start of the SHA-256 of its liveliness key."""
    return hashlib.sha256(token.encode()).digest()[:GID_SIZE]


def encode_attachment(seq: int, publish_time_ns: int, gid_bytes: bytes) -> bytes:
    return _ATT.pack(seq, publish_time_ns, GID_SIZE) + gid_bytes


def decode_attachment(data: bytes) -> tuple[int, int, bytes]:
    """(seq, publish time ns, gid); ValueError for anything else."""
    if len(data) != ATTACHMENT_SIZE or data[_ATT.size - 1] != GID_SIZE:
        raise ValueError(f"not an rmw_zenoh attachment: {len(data)} bytes")
    seq, t_ns, _ = _ATT.unpack_from(data)
    return seq, t_ns, bytes(data[_ATT.size:])


class Ros2Out:
    """One outbound topic under its ROS 2 key: a publisher (CDR), its token, its matching.
    `layout_hash` is the md's as this bridge loaded it: the codec must have the same layout."""

    _ids = iter(range(1, 1 << 30))
    _ids_lock = threading.Lock()

    def __init__(self, session: Any, domain: int, node: str, topic: str, md_name: str,
                 layout_hash: int, depth: int, on_matching: Any) -> None:
        import zenoh

        with self._ids_lock:
            entity_id = next(self._ids)
        zid = str(session.zid())
        self._codec = codec(md_name)
        if self._codec.layout_hash != layout_hash:
            raise ValueError(f"md '{md_name}' changed while loaded: layout hash "
                             f"{self._codec.layout_hash:016x} here, {layout_hash:016x} in use")
        self.key = data_key(domain, topic, md_name)
        self.token_key = publisher_token(domain, zid, node, entity_id, topic, md_name, depth)
        self._gid = gid(self.token_key)
        self.publisher = session.declare_publisher(  # zenoh/bytes, as rmw_zenoh's
            self.key, encoding=zenoh.Encoding.ZENOH_BYTES)
        self.matching = self.publisher.matching_status.matching
        self._listener = self.publisher.declare_matching_listener(
            lambda status: on_matching(self, status.matching))
        self._token = session.liveliness().declare_token(self.token_key)

    def put(self, message: Any, seq: int, publish_time_ns: int) -> None:
        """Publish one sample (`message`: the md's struct, or its raw bytes) as CDR."""
        self.publisher.put(self._codec.encode(message),
                           attachment=encode_attachment(seq, publish_time_ns, self._gid))

    def close(self) -> None:
        for thing in (self._token, self._listener, self.publisher):
            thing.undeclare()
