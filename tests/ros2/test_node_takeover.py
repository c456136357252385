"""The ROS 2 node's topics follow a takeover (5.5), without ROS 2.

:class:`cfgplan.ros2.node.RclpyEvents` on a stand-in node (its publishers keep
what they are given; ``std_msgs/msg/String`` stands in too): a helper's
``/cfgplan/configuration`` is the first configuration; once its robot takes
over, it is the configuration the robot coordinates (none while it stopped
safely, then its switch's), and ``takeover`` and ``step-down`` are on
``/cfgplan/events``; stepped down, it keeps the last. The real node is
tested with ROS 2 in tests/ros2/test_rclpy_node.py (the ``ros2`` set). The
rmw_zenoh layout's bridge sends the two events too.

Before, the node took the configuration from the coordinator its process ran
when it started, if any: a helper that took over published the first
configuration for good.
"""

from __future__ import annotations

import json
from types import SimpleNamespace
from typing import Any

import pytest

from cfgplan.reconfigure.network import NetworkAdaptive
from cfgplan.reconfigure.succession import Steward
from cfgplan.ros2 import node as ros_node
from cfgplan.ros2.bridge import BridgeOptions
from cfgplan.ros2.node import CONFIGURATION_TOPIC, RclpyEvents
from cfgplan.runtime.events import Adaptation
from tests.backends.support import cross_door_44, planned


class _Publisher:
    def __init__(self) -> None:
        self.sent: list[dict[str, Any]] = []

    def publish(self, payload: bytes) -> None:
        length = int.from_bytes(payload[4:8], "little")  # CDR: header, length, text, NUL
        self.sent.append(json.loads(payload[8 : 8 + length - 1]))


class _Node:
    def __init__(self) -> None:
        self.topics: dict[str, _Publisher] = {}

    def create_publisher(self, message: object, topic: str, profile: object) -> _Publisher:
        return self.topics.setdefault(topic, _Publisher())


class _Ros:
    def __init__(self) -> None:
        self.node = _Node()

    def profile(self, qos: object) -> None:
        return None


def _coordinating(running: object) -> NetworkAdaptive:
    """A coordinator role whose reconfigurator runs ``running`` (all the node reads)."""
    role = NetworkAdaptive.__new__(NetworkAdaptive)
    role.coordinator = SimpleNamespace(reconfigurator=SimpleNamespace(running=running))  # type: ignore[assignment]
    return role


def test_the_configuration_topic_follows_the_robot_that_takes_over(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setattr(ros_node, "message_class", lambda name: object)
    _, first = cross_door_44()
    _, other = planned("cross-door/domain.lisp", "cross-door/state-6.2.2-step1.lisp", 2)
    ros = _Ros()
    events = RclpyEvents(ros, "Emil", first)  # type: ignore[arg-type]
    steward = Steward(SimpleNamespace(), lambda following: _coordinating(None))  # type: ignore[arg-type]
    events.follow(steward)
    configuration = ros.node.topics[CONFIGURATION_TOPIC]
    topic = ros.node.topics["/cfgplan/events"]

    def event(what: str, t: float, **info: object) -> None:
        events(Adaptation(robot="Emil", t=t, what=what, info=tuple(info.items())))

    event("install", 1.0, id=1, epoch="1.ab", leader="Pippi")  # a helper's view: as it started
    steward.role = _coordinating(None)  # Emil takes over, and stops safely
    event("takeover", 2.0, epoch="2.cd", after="Pippi", step=0, goal="g", waited=0.3)
    event("no-configuration", 2.1, id=1, cause="takeover from Pippi")
    steward.role.coordinator.reconfigurator.running = other  # type: ignore[attr-defined]
    event("switch", 3.0, id=2, cause="Pippi recovered")
    steward.role = SimpleNamespace()  # type: ignore[assignment]  # he steps down
    event("step-down", 4.0, leader="Pippi", epoch="3.ef", was="2.cd")
    shown = [(r.get("t"), r["running"], r.get("cost")) for r in configuration.sent]
    assert shown == [
        (None, True, first.cost),
        (2.0, False, None),
        (2.1, False, None),
        (3.0, True, other.cost),
        (4.0, True, other.cost),  # stepped down: the last it coordinated
    ]
    assert [r["event"] for r in topic.sent] == [
        "takeover",
        "no-configuration",
        "switch",
        "step-down",
    ]
    assert {"takeover", "step-down"} <= BridgeOptions().events
