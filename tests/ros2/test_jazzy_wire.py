"""The rmw_zenoh layout against real ROS 2 Jazzy (the ``ros2`` set).

Not against rosbags (the library cfgplan's encoder uses), but against what a
Jazzy node itself does: rclpy's ``serialize_message`` / ``deserialize_message``
(Fast CDR, the serializer rmw_zenoh and rmw_fastrtps share) and the type
descriptions and RIHS01 hashes Jazzy's packages ship
(``share/<pkg>/msg/<Name>.json``). For every message type of the packages a
topic map can use that this ROS 2 has (std, geometry, sensor and nav
messages at least, and builtin_interfaces, ...):

* the type description cfgplan hashes is Jazzy's (fields, type ids,
  capacities, referenced types) and so is its ``RIHS01_`` hash, the last part
  of a topic's key expression;
* a message cfgplan encodes (every field given a value of its own, nested
  messages, arrays and sequences filled) is read by rclpy with those values,
  and a message rclpy serializes (its padding included) is read by cfgplan
  with them;
* the QoS enumerations of the token's QoS field are rmw's as rclpy has them,
  and the names cfgplan makes (node names, topic names) are ones rclpy's
  validators accept.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import pytest

from tests.ros2 import realros

pytestmark = pytest.mark.ros2

PACKAGES = ("std_msgs", "geometry_msgs", "sensor_msgs", "nav_msgs", "builtin_interfaces")
"""The message packages a topic map uses, which the ros2-rclpy extra installs."""


def _wire() -> Any:
    from cfgplan.ros2 import rmw_zenoh

    return rmw_zenoh


def _jazzy_types() -> list[tuple[str, Path]]:
    """Each ``pkg/msg/Name`` of PACKAGES with its Jazzy description file."""
    realros.rclpy()
    from cfgplan.ros2 import codec

    share = realros.share()
    found = [
        (f"{package}/msg/{path.stem}", path)
        for package in PACKAGES
        for path in sorted((share / package / "msg").glob("*.json"))
    ]
    known = [(name, path) for name, path in found if codec.known_type(name)]
    # a type added to Jazzy after rosbags's set (nav_msgs/msg/Goals) is one a map
    # cannot name (an error at load_map), so there is nothing of it to check
    assert len(known) > 80 and len(found) - len(known) <= 5, sorted(set(found) - set(known))
    return known


def test_every_type_description_and_hash_is_jazzys() -> None:
    """cfgplan's type description (without default values, which REP-2016
    leaves out of the hash) and RIHS01 hash of each type equal Jazzy's own."""
    wire = _wire()
    fielddefs = wire._typestore().fielddefs
    wrong = []
    for name, path in _jazzy_types():
        jazzy = json.loads(path.read_text("utf-8"))
        described = jazzy["type_description_msg"]
        for one in (described["type_description"], *described["referenced_type_descriptions"]):
            for field in one["fields"]:
                field.pop("default_value")
        hashes = {h["type_name"]: h["hash_string"] for h in jazzy["type_hashes"]}
        if wire._type_description(name, fielddefs) != described:
            wrong.append(f"{name}: description")
        if wire.type_hash(name) != hashes[name]:
            wrong.append(f"{name}: {wire.type_hash(name)} != {hashes[name]}")
    assert not wrong, wrong
    assert wire.type_hash("std_msgs/msg/Char").startswith("RIHS01_3ad2d04d")


def _base(base: str, bound: int, n: int) -> Any:
    """A value of ``base`` that is this field's own (``n``), exact in float32."""
    if base == "bool":
        return n % 2 == 1
    if base in ("string", "wstring"):
        text = f"s{n}é" if base == "string" else f"w{n}"
        return text[:bound] if bound else text
    if base in ("float32", "float64"):
        return n + 0.5
    if base.startswith("int"):
        return -(n % 100) - 1
    return n % 200 + 1  # uint*, byte, char, octet


def _sample(msg_type: str, counter: list[int]) -> dict[str, Any]:
    """A value of every field of ``msg_type``, each distinct, as cfgplan's codec takes it."""
    _, fields = _wire()._typestore().fielddefs[msg_type]
    out: dict[str, Any] = {}
    for name, (kind, desc) in fields:
        if name != _wire().EMPTY_MEMBER:  # on the wire, not a field (std_msgs/msg/Empty)
            counter[0] += 1
            out[name] = _node(kind, desc, counter)
    return out


def _node(kind: int, desc: Any, counter: list[int]) -> Any:
    if kind == 2:  # a nested message
        return _sample(desc, counter)
    if kind in (3, 4):  # T[n], T[] / T[<=n]
        (element_kind, element), size = desc
        count = size if kind == 3 else (min(size, 2) if size else 2)
        items = []
        for _ in range(count):
            counter[0] += 1
            items.append(_node(element_kind, element, counter))
        return items
    base, bound = desc
    return _base(base, bound, counter[0])


def _ros_message(msg_type: str, value: dict[str, Any]) -> Any:
    """rclpy's message of ``msg_type`` holding ``value``."""
    _, fields = _wire()._typestore().fielddefs[msg_type]
    message = realros.message_class(msg_type)()
    for name, (kind, desc) in fields:
        if name in value:
            setattr(message, name, _ros_field(kind, desc, value[name]))
    return message


def _ros_field(kind: int, desc: Any, value: Any) -> Any:
    if kind == 2:
        return _ros_message(desc, value)
    if kind in (3, 4):
        (element_kind, element), _ = desc
        return [_ros_field(element_kind, element, v) for v in value]
    if desc[0] == "byte":
        return bytes([value])
    return value


def _plain(value: Any) -> Any:
    """An rclpy message (or field) as plain values, to compare with cfgplan's."""
    if hasattr(value, "get_fields_and_field_types"):
        return {name: _plain(getattr(value, name)) for name in value.get_fields_and_field_types()}
    if isinstance(value, bytes):
        return value[0] if len(value) == 1 else list(value)
    if hasattr(value, "tolist"):  # array.array, numpy
        return [_plain(v) for v in value.tolist()]
    if isinstance(value, list | tuple):
        return [_plain(v) for v in value]
    if isinstance(value, float) and math.isnan(value):
        return "nan"
    return value


def test_every_message_crosses_between_cfgplan_and_rclpy() -> None:
    """Each type, every field its own value: cfgplan's CDR read by rclpy's
    ``deserialize_message`` gives those values; rclpy's ``serialize_message``
    (Fast CDR, its padding and all) read by cfgplan gives them too; and the
    bytes are the same up to padding (cfgplan's, re-serialized by rclpy, are
    as long as rclpy's own)."""
    from rclpy.serialization import deserialize_message, serialize_message

    from cfgplan.ros2 import codec

    wrong = []
    for name, _ in _jazzy_types():
        value = _sample(name, [0])
        ours = codec.cdr_of_value(name, value)
        theirs = serialize_message(_ros_message(name, value))
        cls = realros.message_class(name)
        read_by_ros = _plain(deserialize_message(ours, cls))
        read_by_us = codec.value_of_cdr(name, theirs)
        if read_by_ros != value:
            wrong.append(f"{name}: rclpy reads {read_by_ros} for {value}")
        if read_by_us != value:
            wrong.append(f"{name}: cfgplan reads {read_by_us} for {value}")
        if len(serialize_message(deserialize_message(ours, cls))) != len(theirs):
            wrong.append(f"{name}: {len(ours)} bytes against rclpy's {len(theirs)}")
        if ours[:4] != theirs[:4]:
            wrong.append(f"{name}: header {ours[:4].hex()} against {theirs[:4].hex()}")
    assert not wrong, "\n".join(wrong[:10])


def test_the_qos_enumerations_and_names_are_rclpys() -> None:
    """The numbers in a token's QoS field are rmw's enumerations (rclpy's
    policies), and the node and topic names cfgplan makes pass rclpy's
    validators; a name cfgplan refuses, rclpy refuses too."""
    realros.rclpy()
    from rclpy.qos import DurabilityPolicy, HistoryPolicy, ReliabilityPolicy
    from rclpy.validate_full_topic_name import validate_full_topic_name
    from rclpy.validate_node_name import validate_node_name

    from cfgplan.ros2.bridge import channel_topic

    wire = _wire()
    assert wire.DEFAULT_QOS.reliability == ReliabilityPolicy.RELIABLE.value
    assert wire.DEFAULT_QOS.durability == DurabilityPolicy.VOLATILE.value
    assert wire.DEFAULT_QOS.history == HistoryPolicy.KEEP_LAST.value
    assert wire.QoS(reliability=2).reliability == ReliabilityPolicy.BEST_EFFORT.value
    assert wire.QoS(durability=1).durability == DurabilityPolicy.TRANSIENT_LOCAL.value
    for text in ("cfgplan_Emil", "robot-1", "1st", "Pippi's base"):
        assert validate_node_name(wire.node_name_of(text))
    for data in (("pos", "Pippi", "Door1"), ("global-orient", "Emil"), ("at", "2nd")):
        assert validate_full_topic_name(channel_topic(data))
    for bad in ("scan", "/a//b", "/1a", "/a b"):
        with pytest.raises(ValueError):
            wire.check_name(bad, "topic name")
        with pytest.raises(Exception, match="topic name"):
            validate_full_topic_name(bad)
