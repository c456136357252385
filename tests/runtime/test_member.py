"""A robot's side of the switch protocol (5.5, cfgplan.runtime.member): what
it sends the coordinator."""

from __future__ import annotations

import json
from typing import Any

from cfgplan.backends.part import runtime_part
from cfgplan.backends.wiring import deploy
from cfgplan.runtime import Registry, society
from cfgplan.runtime.member import Member
from cfgplan.runtime.monitor import Detection, Monitor
from tests.backends.support import EXAMPLE_IMPL, cross_door_44


class Network:
    """Keeps what is published; nothing is delivered."""

    society = "test"

    def __init__(self) -> None:
        self.sent: list[tuple[str, dict[str, Any]]] = []

    def subscribe(self, key: str, handler: object) -> None:
        pass

    def publish(self, key: str, payload: bytes) -> None:
        self.sent.append((key, json.loads(payload)))


def test_a_report_says_which_configuration_the_robot_ran() -> None:
    """The coordinator places a report by the configuration it was made under,
    not by the robot's clock (which may differ from the coordinator's)."""
    problem, config = cross_door_44()
    parts = [runtime_part(p) for p in deploy(config, problem.domain)]
    running = society(parts, Registry.load(EXAMPLE_IMPL))
    emil = next(r for r in running.robots if r.name == "Emil")
    network, monitor = Network(), Monitor()
    member = Member(emil, network, monitor)
    seen = Detection("lost", "Emil", 12.5, other="Pippi")
    for current in (0, 3):
        member.current = current  # as after installing configuration 3
        monitor.detect(seen)
        member.report()
    reports = [m for _, m in network.sent if m["type"] == "report"]
    assert [Detection.read(json.dumps(m["detection"]).encode()) for m in reports] == [
        Detection("lost", "Emil", 12.5, other="Pippi", config=0),
        Detection("lost", "Emil", 12.5, other="Pippi", config=3),
    ]
