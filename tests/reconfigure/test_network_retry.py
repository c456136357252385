"""A robot alive but silent in a switch is tried again (5.5): without it, a
robot whose prepare message was lost would stay out for good, since its
liveliness token never went away and it is never *seen* again.

No network here: the deployer talks to a fake network that records what is
sent and answers nothing unless told; the clock is stepped by hand.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from types import SimpleNamespace

from cfgplan.planner import plan
from cfgplan.problem import load
from cfgplan.reconfigure.coordinate import Coordinator
from cfgplan.reconfigure.network import (
    RETRY,
    RETRY_MOST,
    SWITCH_TIMEOUT,
    NetworkAdaptive,
    NetworkDeployer,
)
from cfgplan.reconfigure.policy import Reconfigurator
from cfgplan.runtime.events import Adaptation, Event
from cfgplan.runtime.monitor import Detection, Monitor
from cfgplan.runtime.part import Part
from cfgplan.runtime.protocol import Ready, encode
from tests.reconfigure.test_coordinate import STEP2, Clock


@dataclass
class Network:
    society: str = "retry-test"
    alive: set[str] = field(default_factory=lambda: {"Emil", "Pippi"})
    sent: list[tuple[str, dict[str, object]]] = field(default_factory=list)

    def publish(self, key: str, payload: bytes) -> None:
        self.sent.append((key, json.loads(payload)))

    def to(self, robot: str, op: str) -> list[dict[str, object]]:
        return [m for k, m in self.sent if k.endswith(f"/{robot}/configure") and m["op"] == op]


@dataclass
class Me:
    """The coordinating robot's member: only what the deployer asks of it."""

    @dataclass
    class _Robot:
        name: str = "Emil"

    robot: _Robot = field(default_factory=_Robot)
    installed: list[int] = field(default_factory=list)
    errors: list[str] = field(default_factory=list)

    def error(self, message: str) -> None:
        self.errors.append(message)

    def install(self, number: int, part: Part) -> None:
        self.installed.append(number)

    def refusal(self, part: Part) -> str | None:
        return None  # it runs every part


class Idle:
    """No injections."""

    def __call__(self, cycle: int, elapsed: float) -> None:
        return None


def _society() -> tuple[NetworkAdaptive, Network, Clock, list[Event]]:
    problem = load(*STEP2)
    configs, _ = plan(problem.task, problem.goal_call)
    reconfigurator = Reconfigurator(problem.task, problem.domain, problem.goal_call, configs[0])
    network, clock, events = Network(), Clock(), []
    deployer = NetworkDeployer(network, Me(), clock=clock)  # type: ignore[arg-type]
    coordinator = Coordinator(reconfigurator, events.append, "Emil", deployer, clock)
    adaptive = NetworkAdaptive(coordinator, deployer, Monitor(), Idle())  # type: ignore[arg-type]
    for robot in sorted(network.alive - {"Emil"}):  # each says its subscriber exists
        adaptive.receive(encode(Ready(robot)))
    return adaptive, network, clock, events


def _wait(adaptive: NetworkAdaptive, clock: Clock, seconds: float) -> None:
    clock.now += seconds
    adaptive.between(0, 0.0)


def _what(events: list[Event]) -> list[tuple[str, str]]:
    return [
        (e.what, str(dict(e.info).get("how", dict(e.info).get("reason", ""))))
        for e in events
        if isinstance(e, Adaptation)
    ]


def test_a_silent_robot_still_alive_is_tried_again_and_rejoins() -> None:
    """Emil's compass fails; the switch needs Pippi, whose prepare goes
    unanswered: the switch is aborted and she is taken as lost. Nothing is
    admissible without her, so Emil stops, and tells her so too, since she is
    alive: unanswered again, aborted again. Alive all the while, she is tried
    again 2·RETRY seconds later (her second silence in a row), answers this
    time, and the society switches to the configuration with her (6.2.2
    step 2: 47)."""
    adaptive, network, clock, events = _society()
    compass = Detection("failure", "Emil", 1.0, instance=("compass", "Emil"), how="injected")
    adaptive.take(compass)
    assert len(network.to("Pippi", "prepare")) == 1
    _wait(adaptive, clock, SWITCH_TIMEOUT + 0.1)
    assert _what(events)[-2:] == [("abort", "silent"), ("failure", "silent")]
    assert "Pippi" in adaptive.coordinator.reconfigurator.situation.lost
    assert len(network.to("Pippi", "prepare")) == 2  # the stop
    _wait(adaptive, clock, SWITCH_TIMEOUT + 0.1)
    assert _what(events)[-1] == ("abort", "silent")
    _wait(adaptive, clock, 2 * RETRY - 0.1)  # not yet
    assert ("recovery", "retry") not in _what(events)
    assert len(network.to("Pippi", "prepare")) == 2
    _wait(adaptive, clock, 0.1)
    assert _what(events)[-1] == ("recovery", "retry")
    assert "Pippi" not in adaptive.coordinator.reconfigurator.situation.lost
    prepare = network.to("Pippi", "prepare")[-1]
    assert len(network.to("Pippi", "prepare")) == 3
    number = int(str(prepare["id"]))
    adaptive.deployer.acked("Pippi", number, "ready", "")
    adaptive.deployer.acked("Pippi", number, "installed", "")
    running = adaptive.coordinator.reconfigurator.running
    assert running is not None and running.cost == 47 and "Pippi" in running.agents
    assert adaptive.deployer.silent == {}


def test_each_silence_in_a_row_doubles_the_wait_and_an_answer_resets_it() -> None:
    network, clock = Network(), Clock()
    deployer = NetworkDeployer(network, Me(), clock=clock)  # type: ignore[arg-type]
    deployer.said_ready("Pippi")
    aborted: list[list[str]] = []
    waits = []
    for number in range(1, 8):
        decision = SimpleNamespace(id=number)
        parts = {"Pippi": Part("Pippi", (), ())}
        deployer.deploy(decision, parts, lambda: None, lambda robots, _: aborted.append(robots))  # type: ignore[arg-type]
        assert deployer.due() == []  # not while a switch is on
        clock.now += SWITCH_TIMEOUT + 0.1
        deployer.tick()
        waits.append(deployer.silent["Pippi"] - clock.now)
        clock.now += waits[-1] - 0.01
        assert deployer.due() == []
        clock.now += 0.01
        assert deployer.due() == ["Pippi"]
    assert aborted == [["Pippi"]] * 7
    assert waits == [min(RETRY * 2**n, RETRY_MOST) for n in range(7)]
    deployer.deploy(SimpleNamespace(id=8), parts, lambda: None, lambda *_: None)  # type: ignore[arg-type]
    deployer.acked("Pippi", 8, "ready", "")  # she answers: the next silence waits RETRY
    deployer.deploy(SimpleNamespace(id=9), parts, lambda: None, lambda *_: None)  # type: ignore[arg-type]
    clock.now += SWITCH_TIMEOUT + 0.1
    deployer.tick()
    assert deployer.silent["Pippi"] - clock.now == RETRY


def test_a_silent_robot_that_is_gone_is_left_to_liveliness() -> None:
    """Not alive any more: nothing is tried; it comes back by being seen."""
    adaptive, network, clock, events = _society()
    adaptive.take(Detection("failure", "Emil", 1.0, instance=("compass", "Emil")))
    _wait(adaptive, clock, SWITCH_TIMEOUT + 0.1)
    network.alive.discard("Pippi")
    _wait(adaptive, clock, RETRY_MOST)
    assert ("recovery", "retry") not in _what(events)
    assert adaptive.deployer.silent == {} and adaptive.deployer._wait == {}
