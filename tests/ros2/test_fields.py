"""Several ports in one ROS 2 message, published outputs and subscribed inputs.

Offline: the cross-door example map (examples/cross-door/ros2-map.toml) read
against the domain; ports to PoseStamped fields and back (the yaw of a
quaternion); its mistakes named with file and line; and the bindings on a
stand-in Zenoh session: a published output goes out as CDR rosbags decodes, a
subscribed input replaces what the channel gave the action.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import pytest

from cfgplan.problem import load
from cfgplan.ros2 import rmw_zenoh as wire
from cfgplan.ros2.bindings import TopicBindings
from cfgplan.ros2.fields import FieldMap, check_path, message_of_ports, ports_of_message
from cfgplan.ros2.topics import load_map, parse_map
from cfgplan.runtime.errors import RunError
from cfgplan.runtime.faults import ResourceFailure
from cfgplan.runtime.registry import Implementation, Registry
from tests.backends.support import DOMAINS, ROOT

typesys = pytest.importorskip("rosbags.typesys")

STORE = typesys.get_typestore(typesys.Stores.ROS2_JAZZY)
POSE = "geometry_msgs/msg/PoseStamped"
MAP = ROOT / "examples" / "cross-door" / "ros2-map.toml"
CROSS = load(DOMAINS / "cross-door/domain.lisp", DOMAINS / "cross-door/state-6.2.2-step1.lisp")
DOOR = FieldMap(("pos", "orient"), (("pose.position.x", "pose.position.y"), "pose.orientation.yaw"))


def test_the_example_map_publishes_transform_info_and_feeds_cross_door() -> None:
    """Two bindings of two ports each on /door_estimate, one publishing, one subscribing."""
    found = load_map(MAP, CROSS.domain, CROSS.task.agents)
    estimate, action = found.bindings
    assert (estimate.functionality, estimate.direction, estimate.mode) == (
        "transform-info",
        "output",
        "publish",
    )
    assert (estimate.ports, estimate.indices) == (("pos", "orient"), (1, 0))  # :out orient, pos
    assert (action.functionality, action.direction, action.mode) == (
        "cross-door",
        "input",
        "subscribe",
    )
    assert (action.ports, action.indices, action.objects) == (("pos", "orient"), (0, 1), 1)
    assert estimate.fields == action.fields == DOOR
    assert estimate.frame_id == "pippi/base_link" and (estimate.robot, action.robot) == (
        "Emil",
        "Pippi",
    )
    # transform-info computes what it publishes, and cross-door's Python runs: both need impl.py
    assert not found.implements("transform-info", "Emil")
    assert not found.implements("cross-door", "Pippi")


def test_ports_become_pose_fields_and_come_back() -> None:
    """pos [x, y] is the position, orient the yaw of the quaternion; the header is stamped."""
    message = message_of_ports(
        POSE, DOOR, [(0.695, -2.601), -0.929], 1_700_000_000_123_456_789, "f"
    )
    assert message["header"] == {
        "stamp": {"sec": 1_700_000_000, "nanosec": 123_456_789},
        "frame_id": "f",
    }
    q = message["pose"]["orientation"]
    assert (q["x"], q["y"]) == (0.0, 0.0) and math.isclose(q["z"] ** 2 + q["w"] ** 2, 1.0)
    assert math.isclose(2 * math.atan2(q["z"], q["w"]), -0.929)
    pos, orient = ports_of_message(DOOR, message)
    assert pos == [0.695, -2.601] and math.isclose(orient, -0.929, abs_tol=1e-12)
    with pytest.raises(ValueError, match=r"port pos: \[1.0\] is not a list of 2 values"):
        message_of_ports(POSE, DOOR, [[1.0], 0.0], 0)
    with pytest.raises(ValueError, match=r"pose\.orientation\.yaw: 'north' is not an angle"):
        message_of_ports(POSE, DOOR, [[1.0, 2.0], "north"], 0)


def test_a_field_path_is_checked_against_the_type() -> None:
    assert check_path(POSE, "pose.orientation.yaw") == "pose.orientation.yaw"
    assert check_path(POSE, "pose") == "pose"
    with pytest.raises(ValueError, match=r"pose.position has no field 'w' \(its fields: x, y, z\)"):
        check_path(POSE, "pose.position.w")
    with pytest.raises(ValueError, match=r"pose\.position\.x of .* has no fields"):
        check_path(POSE, "pose.position.x.y")
    with pytest.raises(ValueError, match="its fields: x, y, z, w, yaw"):
        check_path(POSE, "pose.orientation.roll")


BIND = """
[[bind]]
functionality = "transform-info"
output = {output}
mode = "{mode}"
topic = "/door_estimate"
type = "geometry_msgs/msg/PoseStamped"
{fields}
"""


PORTS = '["pos", "orient"]'


@pytest.mark.parametrize(
    ("output", "mode", "fields", "message", "line"),
    [
        (PORTS, "publish", "", "2 ports in one geometry_msgs/msg/PoseStamped: give fields", 4),
        (
            PORTS,
            "publish",
            'fields = { pos = "pose.position" }',
            "fields names the ports pos: give exactly pos, orient",
            8,
        ),
        ('"pos"', "publish", 'fields = { pos = ["pose.q"] }', "pose has no field 'q'", 8),
        ('"pos"', "send", "", "mode 'send' is not one of: subscribe, publish", 5),
        ('["pos", "pos"]', "publish", "", "output is a port's name or a list of them", 4),
        ('"pos"', "publish", "frame_id = 3", "frame_id 3 is not a string", 8),
    ],
)
def test_a_wrong_multi_port_binding_is_said_with_its_line(
    output: str, mode: str, fields: str, message: str, line: int
) -> None:
    text = BIND.format(output=output, mode=mode, fields=fields)
    with pytest.raises(RunError) as caught:
        parse_map(text, "map.toml", CROSS.domain, CROSS.task.agents)
    assert message in caught.value.message
    assert (caught.value.file, caught.value.line) == ("map.toml", line)


class Declared:
    def __init__(self, key: str, log: list[tuple[str, bytes, bytes]]) -> None:
        self.key, self.log = key, log

    def put(self, payload: bytes, *, attachment: bytes) -> None:
        self.log.append((self.key, payload, attachment))

    def undeclare(self) -> None:
        pass


class Session:
    """What TopicBindings uses of a zenoh-python session."""

    def __init__(self) -> None:
        self.puts: list[tuple[str, bytes, bytes]] = []
        self.tokens: list[str] = []
        self.subscribers: dict[str, Callable[[Any], None]] = {}

    def zid(self) -> str:
        return "0123456789abcdef0123456789abcdef"

    def liveliness(self) -> Session:
        return self

    def declare_token(self, key: str) -> Declared:
        self.tokens.append(key)
        return Declared(key, self.puts)

    def declare_publisher(self, key: str) -> Declared:
        return Declared(key, self.puts)

    def declare_subscriber(self, key: str, receive: Callable[[Any], None]) -> Declared:
        self.subscribers[key] = receive
        return Declared(key, self.puts)

    def is_closed(self) -> bool:
        return False


class Payload:
    def __init__(self, data: bytes) -> None:
        self.data = data

    def __len__(self) -> int:
        return len(self.data)

    def to_bytes(self) -> bytes:
        return self.data


class Sample:
    def __init__(self, data: bytes) -> None:
        self.payload = Payload(data)


def _pose(x: float, y: float, yaw: float) -> bytes:
    types = STORE.types
    message = types[POSE](
        header=types["std_msgs/msg/Header"](
            stamp=types["builtin_interfaces/msg/Time"](sec=1, nanosec=0), frame_id="ros"
        ),
        pose=types["geometry_msgs/msg/Pose"](
            position=types["geometry_msgs/msg/Point"](x=x, y=y, z=0.0),
            orientation=types["geometry_msgs/msg/Quaternion"](
                x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2)
            ),
        ),
    )
    return bytes(STORE.serialize_cdr(message, POSE))


def test_the_helper_publishes_and_the_action_takes_the_topic_over_its_channel() -> None:
    """On a stand-in session: transform-info's pos and orient go out as one PoseStamped
    (rosbags reads them back); cross-door receives the topic's pose, not the
    channel's values; no message yet: it is not called; silent: it fails."""
    found = load_map(MAP, CROSS.domain, CROSS.task.agents)
    received: list[tuple[Any, ...]] = []
    base = Registry(
        [
            Implementation("transform-info", lambda *a: (-0.929, [0.695, -2.601])),
            Implementation("cross-door", lambda *a: received.append(a)),
        ]
    )
    emil_session = Session()
    emil = TopicBindings(emil_session, "Emil", found).registry(base)
    assert emil.lookup("transform-info")("Pippi", "Door1", 0, 0, 0, 0) == (-0.929, [0.695, -2.601])
    hash_ = wire.type_hash(POSE)
    ((key, payload, extra),) = emil_session.puts
    assert key == f"0/door_estimate/geometry_msgs::msg::dds_::PoseStamped_/{hash_}"
    pose = STORE.deserialize_cdr(payload, POSE)
    assert (pose.pose.position.x, pose.pose.position.y) == (0.695, -2.601)
    assert math.isclose(2 * math.atan2(pose.pose.orientation.z, pose.pose.orientation.w), -0.929)
    assert pose.header.frame_id == "pippi/base_link" and pose.header.stamp.sec > 1_700_000_000
    assert wire.parse_attachment(extra).sequence_number == 1

    pippi_session = Session()
    bound = TopicBindings(pippi_session, "Pippi", found)
    pippi = bound.registry(base)
    assert any("/MS/" in t and "%door_estimate" in t for t in pippi_session.tokens)
    cross = pippi.lookup("cross-door")
    assert cross("Door1", [9.0, 9.0], 3.0) is None and received == []  # no message yet
    (receive,) = pippi_session.subscribers.values()
    receive(Sample(_pose(1.5, -0.5, 0.25)))
    cross("Door1", [9.0, 9.0], 3.0)  # the channel's values: replaced by the topic's
    ((door, pos, orient),) = received
    assert door == "Door1" and pos == [1.5, -0.5] and math.isclose(orient, 0.25)
    assert bound.delivered == {bound.bindings[0]: 1}
    assert bound.summary() == [
        "Pippi /door_estimate (geometry_msgs/msg/PoseStamped), cross-door pos, orient: "
        "1 messages received, given to 1 calls"
    ]
    latest = bound.latest[bound.bindings[0]]
    assert latest.at is not None
    latest.at -= 1.5  # silent past the 1 s timeout: the action's call fails
    with pytest.raises(ResourceFailure, match=r"topic /door_estimate .* no message for 1\.5 s"):
        cross("Door1", [9.0, 9.0], 3.0)
