"""The monitor of 5.5: failures, staleness, presence and recoveries turned into detections.

A hand-made robot runs a sensing resource (``compass``) feeding an action;
its time is stepped explicitly, so holds and probes are exact.
"""

from __future__ import annotations

import json

import pytest

from cfgplan.runtime import (
    CallSpec,
    ChannelSpec,
    Implementation,
    InProcessTransport,
    Part,
    Registry,
    ResourceFailure,
    Robot,
    build,
)
from cfgplan.runtime.monitor import HOLD_MAX, Detection, Monitor

PART = Part(
    "Emil",
    (ChannelSpec("local", "F2", "F1", ("heading", "Emil")),),
    (
        CallSpec("F2", "compass", (), (), ((0,),)),
        CallSpec("F1", "steer", (), ((0,),), ()),
    ),
)


class Compass:
    """A compass that fails while ``broken``: by raising ResourceFailure, or
    (``silent``) by giving no data."""

    def __init__(self, silent: bool = False) -> None:
        self.broken = False
        self.silent = silent
        self.calls = 0

    def __call__(self) -> float | None:
        self.calls += 1
        if self.broken:
            if self.silent:
                return None
            raise ResourceFailure("magnetic disturbance")
        return 0.3


def _robot(compass: Compass) -> tuple[Robot, Monitor]:
    registry = Registry(
        [Implementation("compass", compass), Implementation("steer", lambda heading: None)]
    )
    robot = build(PART, registry)
    monitor = Monitor(hold=1.0)
    monitor.watch(robot)
    robot.start(0.0, rate=10, budget=None)
    return robot, monitor


def _run(robot: Robot, start: float, end: float) -> None:
    t = start
    while t < end - 1e-9:
        if robot.due(t):
            robot.step(t)
        t = round(t + 0.1, 6)


def test_a_resource_failure_is_detected_once_and_probed_back() -> None:
    compass = Compass()
    robot, monitor = _robot(compass)
    _run(robot, 0.0, 1.0)
    assert monitor.drain() == []
    compass.broken = True
    _run(robot, 1.0, 2.0)
    seen = monitor.drain()
    (failure,) = [d for d in seen if d.kind == "failure"]  # once, though every call fails
    assert [d.kind for d in seen if d.kind != "failure"] == ["stale"]  # its consumer starves
    assert (failure.kind, failure.instance, failure.how, failure.label) == (
        "failure",
        ("compass", "Emil"),
        "reported",
        "F2",
    )
    assert "ResourceFailure: magnetic disturbance" in failure.detail
    compass.broken = False
    _run(robot, 2.0, 2.5)
    assert [d.kind for d in monitor.drain()] == ["fresh"]  # working, not for the hold yet
    _run(robot, 2.5, 4.0)
    (recovery,) = monitor.drain()
    assert (recovery.kind, recovery.instance, recovery.how) == (
        "recovery",
        ("compass", "Emil"),
        "probe",
    )


def test_each_failure_doubles_the_hold() -> None:
    compass = Compass()
    robot, monitor = _robot(compass)
    prober = monitor.probers["Emil"]
    wrapper = robot.wrappers[0]
    for expected in (1.0, 2.0, 4.0):
        prober.failed(("compass", "Emil"), wrapper, "reported")
        assert prober.probes[("compass", "Emil")].hold == expected
    for _ in range(10):
        prober.failed(("compass", "Emil"), wrapper, "reported")
    assert prober.probes[("compass", "Emil")].hold == HOLD_MAX


def test_a_probe_that_fails_again_restarts_the_hold() -> None:
    compass = Compass()
    robot, monitor = _robot(compass)
    compass.broken = True
    _run(robot, 0.0, 0.5)
    monitor.drain()
    compass.broken = False
    _run(robot, 0.5, 1.2)
    compass.broken = True  # flickers back off before the hold is over
    _run(robot, 1.2, 1.5)
    compass.broken = False
    _run(robot, 1.5, 2.4)
    assert "recovery" not in [d.kind for d in monitor.drain()]
    _run(robot, 2.4, 3.0)
    assert "recovery" in [d.kind for d in monitor.drain()]


def test_a_silent_sensor_makes_its_consumer_stale_and_fresh_again() -> None:
    compass = Compass(silent=True)
    robot, monitor = _robot(compass)
    _run(robot, 0.0, 1.0)
    compass.broken = True
    _run(robot, 1.0, 2.0)
    (stale,) = monitor.drain()
    assert (stale.kind, stale.label, stale.other) == ("stale", "F2", "Emil")
    assert abs(stale.limit - 0.3) < 1e-9  # 3 periods of the sender
    compass.broken = False
    _run(robot, 2.0, 2.5)
    assert [d.kind for d in monitor.drain()] == ["fresh"]


def test_an_injected_fault_fails_every_call_without_calling_the_implementation() -> None:
    compass = Compass()
    robot, monitor = _robot(compass)
    robot.faults[("compass", "Emil")] = "fail compass(Emil) at cycle 3"
    robot.wrappers[0].injected = "fail compass(Emil) at cycle 3"
    _run(robot, 0.0, 0.5)
    (failure,) = [d for d in monitor.drain() if d.kind == "failure"]
    assert failure.how == "injected" and compass.calls == 0
    del robot.faults[("compass", "Emil")]
    _run(robot, 0.5, 2.0)
    assert "recovery" in [d.kind for d in monitor.drain()]


def test_robots_lost_and_seen_and_detections_travel_as_json() -> None:
    transport = InProcessTransport()
    monitor = Monitor()
    transport.presence_listeners.append(monitor.presence("Emil"))
    transport.leave("Pippi")
    transport.join("Pippi")
    lost, seen = monitor.drain()
    assert (lost.kind, lost.other, seen.kind, seen.other) == ("lost", "Pippi", "seen", "Pippi")
    for d in (lost, Detection("facts", "Emil", 1.0, added=(("in", "Pippi", "Room2"),))):
        assert Detection.read(d.message()) == d


@pytest.mark.parametrize(
    "field",
    [
        {"config": "x"},
        {"config": True},
        {"t": "soon"},
        {"t": float("inf")},
        {"kind": "exploded"},
        {"instance": "compass"},
        {"instance": ["compass", 1]},
        {"added": [["robot", ["Pippi"]]]},
        {"detail": 3},
    ],
)
def test_a_detection_from_the_network_is_read_field_by_field(field: dict[str, object]) -> None:
    """A report is acted on later (after a switch, from the backlog): one with
    a field of the wrong type is refused where it is read, not met there
    (``"config": "x"`` raised TypeError out of the coordinator's loop)."""
    good = json.loads(Detection("failure", "Pippi", 2.0, instance=("compass", "Pippi")).message())
    assert Detection.read(json.dumps(good).encode()).instance == ("compass", "Pippi")
    with pytest.raises(ValueError):
        Detection.read(json.dumps({**good, **field}).encode())
