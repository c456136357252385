"""rmw_zenoh's wire format (:mod:`cfgplan.ros2.rmw_zenoh`), checked against the
examples of rmw_zenoh's design document (ros2/rmw_zenoh ``docs/design.md``)
and its sources (``liveliness_utils.cpp``, ``attachment_helpers.cpp``,
``qos.cpp``) as released for Jazzy from 0.2.4 (Rolling and Kilted from 0.6.0),
and the attachment against zenoh-ext's own serializer. No ROS 2 installation
is needed: tests/ros2/test_jazzy_wire.py checks the same against real Jazzy."""

from __future__ import annotations

import subprocess
import sys

import pytest
import xxhash
from rosbags.typesys import Stores, get_typestore

from cfgplan.ros2 import codec
from cfgplan.ros2 import rmw_zenoh as wire
from cfgplan.runtime.errors import RunError
from tests.backends.support import ROOT

STRING = "std_msgs::msg::dds_::String_"
STRING_HASH = "RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18"
"""std_msgs/msg/String's type hash, as design.md's examples print it."""


def test_the_type_name_and_hash_of_a_string_are_the_design_documents() -> None:
    """design.md, "Topic and Service name mapping": ``std_msgs::msg::dds_::String_``
    and the RIHS01 hash of its ``chatter`` examples, the hash computed by rosbags."""
    assert wire.dds_type_name("std_msgs/msg/String") == STRING
    assert wire.type_hash("std_msgs/msg/String") == STRING_HASH
    with pytest.raises(ValueError, match="not a ROS 2 type name"):
        wire.dds_type_name("String")


CHAR_HASH = "RIHS01_3ad2d04dd29ba19d04b16659afa3ccaedd691914b02a64e82e252f2fa6a586a9"
"""std_msgs/msg/Char's type hash in Jazzy's own share/std_msgs/msg/Char.json."""


def test_a_char_field_is_described_as_uint8_as_rosidl_does() -> None:
    """A ``.msg`` ``char`` is an IDL ``uint8`` (rosidl_adapter), type id 3: Jazzy's
    hash of std_msgs/msg/Char. rosbags's own ``hash_rihs01`` gives it the IDL
    ``char``'s id, 13, and a hash no real node has (``8914cecc...``)."""
    assert wire.type_hash("std_msgs/msg/Char") == CHAR_HASH
    described = wire._type_description("std_msgs/msg/Char", wire._typestore().fielddefs)
    assert described["type_description"]["fields"][0]["type"]["type_id"] == 3
    store = get_typestore(Stores.ROS2_JAZZY)
    # every type without a char field hashes as rosbags hashes it
    for name in ("std_msgs/msg/String", "sensor_msgs/msg/LaserScan", "nav_msgs/msg/Odometry"):
        assert wire.type_hash(name) == store.hash_rihs01(name)


def test_topic_key_expressions_mirror_the_chatter_examples() -> None:
    """design.md's ``chatter`` topic (domain 0), and the same in namespace ``/robot1``:
    the name loses its leading slash."""
    chatter = wire.topic_key_expr(0, "/chatter", STRING, STRING_HASH)
    assert chatter == f"0/chatter/{STRING}/{STRING_HASH}"
    assert (
        wire.topic_key_expr(0, "/robot1/chatter", STRING, STRING_HASH)
        == f"0/robot1/chatter/{STRING}/{STRING_HASH}"
    )
    assert wire.topic_key_expr(7, "/cfgplan/events", STRING, STRING_HASH).startswith(
        "7/cfgplan/events/std_msgs::msg::dds_::String_/RIHS01_"
    )


def test_a_node_token_mirrors_the_listener_example() -> None:
    """design.md, "Graph Cache": ``@ros2_lv/2/aac3178e146ba6f1fc6e6a4085e77f21/0/0/NN/%/%/listener``
    (root namespace and default enclave mangled to ``%``)."""
    token = wire.node_token(2, "aac3178e146ba6f1fc6e6a4085e77f21", 0, "listener")
    assert token == "@ros2_lv/2/aac3178e146ba6f1fc6e6a4085e77f21/0/0/NN/%/%/listener"
    spaced = wire.node_token(0, "ab", 3, "n", namespace="/robot1/arm")
    assert spaced == "@ros2_lv/0/ab/3/3/NN/%/%robot1%arm/n"


def test_a_publisher_token_mirrors_the_talker_example() -> None:
    """design.md, "Graph Cache": the ``talker`` node's publisher on ``chatter``,
    keep last 7, everything else rmw_zenoh's default."""
    token = wire.publisher_token(
        2, "8b20917502ee955ac4476e0266340d5c", 0, 10, "talker", "/chatter", STRING,
        STRING_HASH, wire.QoS(depth=7),
    )  # fmt: skip
    assert token == (
        "@ros2_lv/2/8b20917502ee955ac4476e0266340d5c/0/10/MP/%/%/talker/%chatter/"
        f"{STRING}/{STRING_HASH}/::,7:,:,:,,"
    )


def test_the_qos_part_leaves_rmw_zenohs_defaults_empty() -> None:
    """``qos_to_keyexpr``: reliable, volatile, keep last 42 are rmw_zenoh's
    defaults (qos.cpp), written as nothing; the listener example's depth 10."""
    assert wire.qos_key_expr(wire.QoS()) == "::,:,:,:,,"
    assert wire.qos_key_expr(wire.QoS(depth=10)) == "::,10:,:,:,,"
    best_effort_transient = wire.QoS(reliability=2, durability=1, history=2, depth=10)
    assert wire.qos_key_expr(best_effort_transient) == "2:1:2,10:,:,:,,"


def test_names_are_mangled_and_checked() -> None:
    """``mangle_name``: every ``/`` becomes ``%``; ROS 2 names are checked before use."""
    assert wire.mangle("/cfgplan/events") == "%cfgplan%events"
    assert wire.check_name("/cfgplan/events", "topic name") == "/cfgplan/events"
    for bad in ("cfgplan/events", "/cfgplan//events", "/9lives", "/a-b", "/"):
        with pytest.raises(ValueError, match="not an absolute ROS 2 topic name"):
            wire.check_name(bad, "topic name")
    assert wire.node_name_of("cfgplan_Emil") == "cfgplan_Emil"
    assert wire.node_name_of("robot-1") == "robot_1"
    assert wire.node_name_of("1st") == "_1st"


def test_the_attachment_has_the_documented_33_bytes() -> None:
    """design.md, "Publishers": 8 bytes sequence number (int64 LE), 8 bytes source
    timestamp (int64 LE), 1 byte GID length (16), the 16-byte GID."""
    gid = bytes(range(16))
    data = wire.attachment(1, 0x0102030405060708, gid)
    assert data == bytes.fromhex(
        "0100000000000000080706050403020110000102030405060708090a0b0c0d0e0f"
    )
    assert len(data) == wire.ATTACHMENT_BYTES == 33
    assert wire.parse_attachment(data) == wire.Attachment(1, 0x0102030405060708, gid)
    with pytest.raises(ValueError, match="16 bytes"):
        wire.attachment(1, 0, b"short")
    with pytest.raises(ValueError, match="not an rmw_zenoh attachment"):
        wire.parse_attachment(data[:-1])


def test_the_attachment_is_zenoh_exts_serialization_of_rmw_zenohs_fields() -> None:
    """attachment_helpers.cpp (Jazzy 0.2.4 on, "Change serialization format"):
    ``zenoh::ext::Serializer`` of an int64, an int64 and a ``std::array<uint8_t,
    16>`` (a sequence: its length first). zenoh-python's ``z_serialize`` of the
    same values gives the same bytes."""
    ext = pytest.importorskip("zenoh.ext")
    gid = bytes(range(100, 116))
    expected = ext.z_serialize(
        (ext.Int64(7), ext.Int64(1_700_000_000_123_456_789), [ext.UInt8(b) for b in gid])
    ).to_bytes()
    assert wire.attachment(7, 1_700_000_000_123_456_789, gid) == expected


def test_the_gid_is_xxh3_128_of_the_token_low_half_first() -> None:
    """liveliness_utils.cpp: the GID is XXH3-128 of the liveliness key expression,
    ``low64`` then ``high64`` copied from memory (little endian): the reverse of
    xxhash's canonical, big-endian digest."""
    token = "@ros2_lv/0/ab/0/1/MP/%/%/n/%t/" + f"{STRING}/{STRING_HASH}/::,10:,:,:,,"
    gid = wire.gid(token)
    assert len(gid) == 16
    assert gid == xxhash.xxh3_128_digest(token.encode())[::-1]
    assert gid != wire.gid(token + "x")


def test_a_string_is_cdr_with_the_encapsulation_header() -> None:
    """design.md, "Serialization/Deserialization": CDR with the 4-byte header
    ``00 01 00 00`` (little endian), then the length (with the NUL) and the bytes;
    it reads back with rosbags' own deserializer."""
    assert wire.string_cdr("hi") == bytes.fromhex("0001000003000000686900")
    text = '{"event": "switch", "robot": "Emil", "note": "Pippi \u00e5"}'
    payload = wire.string_cdr(text)
    assert payload[:4] == b"\x00\x01\x00\x00"
    store = get_typestore(Stores.ROS2_JAZZY)
    assert store.deserialize_cdr(payload, "std_msgs/msg/String").data == text
    assert wire.string_of_cdr(payload) == text
    with pytest.raises(ValueError, match="not a plain CDR payload"):
        wire.string_of_cdr(b"\x01\x02\x00\x00")


def test_bytes_after_the_message_are_padding_and_ignored() -> None:
    """rclpy's ``serialize_message`` pads a sensor_msgs/msg/JointState with 8
    bytes past its last field (not zeros: what was in the buffer); Fast CDR reads
    the message and ignores them, and so does the decoder (rosbags's own
    ``deserialize_cdr`` refused it: "CDR message size mismatch"). A payload
    cut short is still an error."""
    joint = "sensor_msgs/msg/JointState"
    value = {"name": ["a"], "position": [1.0]}
    payload = codec.cdr_of_value(joint, value)
    padded = payload + bytes.fromhex("7c02a6030000ab03")
    got = codec.value_of_cdr(joint, padded)
    assert got["name"] == ["a"] and got["position"] == [1.0] and got["effort"] == []
    assert wire.string_of_cdr(wire.string_cdr("hi") + bytes(5)) == "hi"
    with pytest.raises(ValueError, match="not a CDR sensor_msgs/msg/JointState"):
        codec.value_of_cdr(joint, payload[:-9])


def test_a_missing_extra_is_named(monkeypatch: pytest.MonkeyPatch) -> None:
    """Without rosbags or xxhash, the error names ``pip install 'cfgplan[ros2]'``."""
    monkeypatch.setitem(sys.modules, "xxhash", None)  # type: ignore[arg-type]
    with pytest.raises(RunError, match="xxhash") as caught:
        wire.gid("@ros2_lv/0/a/0/0/NN/%/%/n")
    assert caught.value.hint == "pip install 'cfgplan[ros2]'"
    monkeypatch.setitem(sys.modules, "rosbags", None)  # type: ignore[arg-type]
    monkeypatch.setitem(sys.modules, "rosbags.typesys", None)  # type: ignore[arg-type]
    with pytest.raises(RunError, match="rosbags"):
        wire._module("rosbags.typesys")


def test_the_runtime_and_run_command_do_not_import_the_ros2_extra() -> None:
    """A robot without --ros2 never imports rosbags, xxhash or cfgplan.ros2."""
    code = (
        "import sys, cfgplan.runtime, cfgplan.cli.run\n"
        "print(sorted(m for m in sys.modules if m.split('.')[0] in ('rosbags', 'xxhash')"
        " or m.startswith('cfgplan.ros2')))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, check=True
    )
    assert out.stdout.strip() == "[]"


def test_a_decoded_message_has_its_fields_only() -> None:
    """A type's constants (sensor_msgs/msg/NavSatStatus's STATUS_FIX, ...) are
    attributes of rosbags's classes but no fields of the message, and the one
    byte an empty message has on the wire is none either: the value is what
    rclpy's message holds (tests/ros2/test_jazzy_wire.py compares every type)."""
    status = "sensor_msgs/msg/NavSatStatus"
    got = codec.value_of_cdr(status, codec.cdr_of_value(status, {"status": 2, "service": 1}))
    assert got == {"status": 2, "service": 1}
    empty = "std_msgs/msg/Empty"
    assert codec.value_of_cdr(empty, codec.cdr_of_value(empty, {})) == {}
