"""Running the cost-44 configuration of 4.6 in process: cutting a channel, losing
messages, a failing functionality, bounded memory, events to subscribers."""

from __future__ import annotations

import random
from collections import Counter

import pytest

from cfgplan.backends.part import runtime_part
from cfgplan.backends.wiring import deploy
from cfgplan.runtime import (
    Call,
    ChannelKey,
    Event,
    Implementation,
    InProcessTransport,
    Part,
    Registry,
    Society,
    Transfer,
    build,
    society,
    summary,
)
from tests.backends.support import EXAMPLE_IMPL, cross_door_44


def _parts() -> list[Part]:
    problem, config = cross_door_44()
    return [runtime_part(p) for p in deploy(config, problem.domain)]


def _counting(registry: Registry, calls: Counter[str], fail: str = "") -> Registry:
    """The same implementations, counting how often each actually runs
    (``fail``: that one raises instead)."""

    def counted(impl: Implementation) -> Implementation:
        def run(*args: object) -> object:
            calls[impl.name] += 1
            if impl.name == fail:
                raise OSError("camera unplugged")
            return impl(*args)

        return Implementation(impl.name, run, impl.precondition)

    return Registry(counted(registry.lookup(n)) for n in registry.names())


class Cut(InProcessTransport):
    """A transport that loses everything sent on one channel."""

    def __init__(self, cut: ChannelKey) -> None:
        super().__init__()
        self.cut = cut

    def send(self, key: ChannelKey, robot: str, payload: bytes) -> None:
        if key != self.cut:
            super().send(key, robot, payload)


class Lossy(InProcessTransport):
    """Loses each message with probability ``loss`` (seeded: the same every run)."""

    def __init__(self, loss: float, seed: int = 12) -> None:
        super().__init__()
        self.loss = loss
        self.random = random.Random(seed)
        self.lost = 0

    def send(self, key: ChannelKey, robot: str, payload: bytes) -> None:
        if self.random.random() < self.loss:
            self.lost += 1
            return
        super().send(key, robot, payload)


def test_all_functionalities_run_and_the_action_gets_data_from_cycle_two() -> None:
    calls: Counter[str] = Counter()
    running = society(_parts(), _counting(Registry.load(EXAMPLE_IMPL), calls))
    assert running.run(4) == "cycles"
    assert [r.name for r in running.robots] == ["Pippi", "Emil"]
    assert calls["camera"] == calls["transform-info"] == 4
    assert calls["compass"] == 8  # Emil's and Pippi's
    assert calls["cross-door"] == 3  # the door info crosses to Pippi after Emil's first cycle
    assert running.transport is not None and running.transport.undelivered == 0


def test_a_cut_channel_makes_the_wrappers_skip() -> None:
    """Pippi's global-orient never reaches Emil: measure-robot-orient-compass,
    then transform-info, then cross-door wait; their functions never run."""
    parts = _parts()
    (cut,) = [
        ChannelKey(c.source, c.target, c.data)
        for p in parts
        for c in p.channels
        if c.data == ("global-orient", "Pippi")
    ][:1]
    transport = Cut(cut)
    calls: Counter[str] = Counter()
    registry = _counting(Registry.load(EXAMPLE_IMPL), calls)
    running = Society([build(p, registry, transport) for p in parts])
    running.run(3)
    assert calls["camera"] == 3 and calls["measure-door"] == 3 and calls["compass"] == 6
    assert calls["measure-robot-orient-compass"] == 0
    assert calls["transform-info"] == 0 and calls["cross-door"] == 0
    waiting = {e.name: e.waiting for e in running.calls if e.status == "waiting"}
    assert waiting["measure-robot-orient-compass"] == (("global-orient", "Pippi"),)
    assert waiting["transform-info"] == (("orient", "Emil", "Pippi"),)
    assert waiting["cross-door"] == (("pos", "Pippi", "Door1"), ("orient", "Pippi", "Door1"))
    lines = summary(running.wrappers)
    assert any(
        "measure-robot-orient-compass(Emil, Pippi): ran in 0 of 3 cycles; "
        "waits for global-orient(Pippi)" in line
        for line in lines
    )


def test_one_slot_channels_tolerate_losing_a_fifth_of_the_messages() -> None:
    transport = Lossy(0.2)
    calls: Counter[str] = Counter()
    registry = _counting(Registry.load(EXAMPLE_IMPL), calls)
    running = Society([build(p, registry, transport) for p in _parts()])
    running.run(50)
    sent = transport.sent + transport.lost
    assert 0.1 < transport.lost / sent < 0.3  # the loss happened
    assert 10 < calls["cross-door"] < 49  # fewer runs, but data still arrives
    received = [c for c in running.calls if c.name == "cross-door" and c.status == "ran"]
    assert received and all(c.inputs[0][1] == received[0].inputs[0][1] for c in received)


def test_a_failing_functionality_does_not_stop_the_society() -> None:
    """Emil's camera raises every time: its wrapper reports it, what depends on
    it waits, Pippi's compass and Emil's compass keep running."""
    calls: Counter[str] = Counter()
    running = society(_parts(), _counting(Registry.load(EXAMPLE_IMPL), calls, fail="camera"))
    assert running.run(5) == "cycles"
    assert calls["camera"] == 5 and calls["compass"] == 10
    assert calls["measure-door"] == calls["cross-door"] == 0
    failed = [c for c in running.calls if c.status == "error"]
    assert len(failed) == 5 and all(c.name == "camera" for c in failed)
    assert failed[0].error.startswith("the implementation raised OSError: camera unplugged (")
    (line,) = [x for x in summary(running.wrappers) if "camera(Emil)" in x]
    assert line.startswith("Emil F8 camera(Emil): ran in 0 of 5 cycles; failed 5 times, last: ")


def test_events_reach_subscribers_whole_and_the_robot_keeps_only_the_newest() -> None:
    running = society(_parts(), Registry.load(EXAMPLE_IMPL))
    seen: list[Event] = []
    running.subscribe(seen.append)
    running.run(1200)
    pippi, emil = running.robots
    assert len(pippi.events) == len(emil.events) == 1000  # bounded (EVENTS_KEPT)
    assert len(seen) > 2 * 1000  # every event went to the subscriber
    kinds = Counter(e.kind for e in seen)
    assert kinds["call"] == 1200 * 8
    assert kinds["send"] == kinds["receive"] == 1200 * 3  # three global channels
    sends = [e for e in seen if isinstance(e, Transfer) and e.direction == "send"]
    assert {str(e.channel) for e in sends} == {
        "F10->F12 (global-orient Pippi)",
        "F7->F3 (pos Pippi Door1)",
        "F7->F3 (orient Pippi Door1)",
    }
    assert [e.kind for e in seen[:2]] == ["start", "start"]
    # the counts behind the summary are kept whole
    (cross,) = [w for w in running.wrappers if w.name == "cross-door"]
    assert cross.stats.by_status == {"waiting": 1, "ran": 1199}
    assert isinstance(cross.stats.last, Call)


def test_a_late_cycle_keeps_every_functionality_on_the_beat() -> None:
    """A robot that falls behind skips the turns it missed, and its
    functionalities stay due together: one cycle each, not one per function."""
    now = [0.0]
    (emil_part,) = [p for p in _parts() if p.robot == "Emil"]
    robot = build(emil_part, Registry.load(EXAMPLE_IMPL))
    robot.clock = lambda: now[0]
    robot.start(0.0, rate=10, budget=None)
    robot.step(0.0)
    assert robot.next_due() == pytest.approx(0.1)
    robot.step(0.37)  # 0.27 s late: the turns at 0.1, 0.2 and 0.3 are gone
    assert len({w.next_due for w in robot.wrappers}) == 1
    assert robot.next_due() == pytest.approx(0.4)
    assert not robot.due(0.39) and robot.due(0.4)
    assert all(w.stats.calls == 2 for w in robot.wrappers)
