"""Installing a new part on a running robot with the least disruption (5.5, 7.2).

The cost-44 configuration of 6.2.2 step 2 switches to the camera
configuration (47, Fig. 6.4 bottom) after Emil's compass fails: what both
share keeps running with its state, the rest is stopped or started.
"""

from __future__ import annotations

import threading
import time

import pytest

from cfgplan.backends.part import runtime_part
from cfgplan.backends.wiring import deploy
from cfgplan.planner import plan
from cfgplan.problem import load
from cfgplan.reconfigure.fallbacks import Resource
from cfgplan.reconfigure.policy import Reconfigurator
from cfgplan.runtime import Implementation, Part, Registry, Society, build, install, society
from cfgplan.runtime.events import Call
from cfgplan.runtime.install import Installed, crash
from cfgplan.runtime.part import ChannelSpec
from tests.backends.support import DOMAINS, EXAMPLE_IMPL

STEP2 = (DOMAINS / "cross-door/domain.lisp", DOMAINS / "cross-door/state-6.2.2-step2.lisp")


def _switch() -> tuple[dict[str, Part], dict[str, Part]]:
    """The parts of 44 and of the relabelled 47 (after compass(Emil) fails)."""
    problem = load(*STEP2)
    configs, _ = plan(problem.task, problem.goal_call)
    before = {p.robot: runtime_part(p) for p in deploy(configs[0], problem.domain)}
    r = Reconfigurator(problem.task, problem.domain, problem.goal_call, configs[0])
    decision = r.failed(Resource("functionality", instance=("compass", "Emil"), text="x"))
    assert decision.config is not None and decision.config.cost == 47
    return before, r.parts(decision.previous)


def _registry(stopped: list[tuple[str, ...]]) -> Registry:
    """The example's implementations, with a stop hook that records its calls."""
    base = Registry.load(EXAMPLE_IMPL)

    def hooked(impl: Implementation) -> Implementation:
        def stop(*objects: str) -> None:
            stopped.append((impl.name, *objects))

        return Implementation(impl.name, impl.function, impl.precondition, stop)

    return Registry(hooked(base.lookup(n)) for n in base.names())


def test_shared_parts_keep_running_with_their_state() -> None:
    before, after = _switch()
    stopped: list[tuple[str, ...]] = []
    registry = _registry(stopped)
    running = Society([build(p, registry) for p in before.values()])
    running.run(cycles=3)
    pippi = running.robot("Pippi")
    assert pippi is not None
    channel = next(c for c in pippi.channels if c.data == ("pos", "Pippi", "Door1"))
    wrapper = next(w for w in pippi.wrappers if w.name == "measure-door")
    value, refreshed, calls = channel.peek(), channel.refreshed, wrapper.stats.calls

    done = install(pippi, after["Pippi"])

    assert channel in pippi.channels and wrapper in pippi.wrappers  # the same objects
    assert (channel.peek(), channel.refreshed, wrapper.stats.calls) == (value, refreshed, calls)
    assert sorted(done.stopped) == [
        "F11: compass(Pippi)",
        "F12: measure-robot-orient-compass(Pippi, Emil)",
    ]
    assert sorted(done.started) == [
        "F15: measure-robot-orient-camera(Pippi, Emil)",
        "F18: measure-robot-angle(Pippi, Emil)",
    ]
    assert "F7: transform-info(Pippi, Emil, Door1)" in done.kept
    assert "F12->F7 (orient Pippi Emil)" in done.stopped_channels
    assert "F15->F7 (orient Pippi Emil)" in done.started_channels
    assert sorted(stopped) == [("compass",), ("measure-robot-orient-compass", "Emil")]
    assert [w.label for w in pippi.wrappers] == [c.label for c in after["Pippi"].calls]
    assert install(pippi, after["Pippi"]).changed is False  # the same part again


def test_after_the_switch_the_society_runs_the_new_configuration() -> None:
    before, after = _switch()
    running = society(list(before.values()), Registry.load(EXAMPLE_IMPL))
    running.run(cycles=3)
    door = [c for c in running.calls if c.name == "cross-door" and c.status == "ran"][-1]
    for robot in running.robots:
        install(robot, after[robot.name])
    running.run(cycles=3)
    calls = [c for c in running.calls if c.cycle > 3]
    assert calls and not [c for c in calls if c.name == "compass"]
    again = [c for c in calls if c.name == "cross-door" and c.status == "ran"][-1]
    assert again.cycle > door.cycle
    (pos, orient), (pos2, orient2) = (v for _, v in door.inputs), (v for _, v in again.inputs)
    assert pos2 == pytest.approx(pos) and orient2 == pytest.approx(orient)  # the same door


def test_a_global_channel_that_is_stopped_is_detached() -> None:
    before, after = _switch()
    running = society(list(before.values()), Registry.load(EXAMPLE_IMPL))
    transport = running.transport
    emil, pippi = running.robot("Emil"), running.robot("Pippi")
    assert transport is not None and emil is not None and pippi is not None
    key = next(c.key for c in emil.channels if c.data == ("global-orient", "Emil"))
    transport.send(key, "Pippi", b"{}")
    assert transport.undelivered == 0
    install(pippi, after["Pippi"])
    transport.send(key, "Pippi", b"{}")
    assert transport.undelivered == 1


def test_an_empty_part_stops_everything_and_the_robot_idles() -> None:
    before, _ = _switch()
    stopped: list[tuple[str, ...]] = []
    emil = build(before["Emil"], _registry(stopped))
    done = install(emil, Part("Emil", (), ()))
    assert emil.wrappers == [] and emil.channels == []
    assert ("cross-door", "Door1") in stopped and len(done.stopped) == 2
    running = Society([emil])
    assert running.run(cycles=5, rate=200) == "cycles"  # it still ticks at its rate
    assert emil.cycles == 5


def test_a_crash_calls_no_stop_hook() -> None:
    before, _ = _switch()
    stopped: list[tuple[str, ...]] = []
    emil = build(before["Emil"], _registry(stopped))
    crash(emil)
    assert stopped == [] and emil.wrappers == [] and all(w.stopped for w in emil.retired)


def test_a_global_channel_whose_other_end_moved_still_receives() -> None:
    """The same labels and data, the sender now on another robot (a new
    configuration numbers its functionalities afresh): a new channel with the
    old one's key. The old end is detached before the new one is attached,
    so the new one receives (the local transport refused it as made twice,
    and Zenoh's replaced the receiver, then dropped it with the old end)."""

    def part(other: str) -> Part:
        return Part("Pippi", (ChannelSpec("global", "F1", "F2", ("x", "Pippi"), other),), ())

    running = society(
        [part("Emil"), Part("Emil", (), ()), Part("Ida", (), ())], Registry.load(EXAMPLE_IMPL)
    )
    pippi, transport = running.robot("Pippi"), running.transport
    assert pippi is not None and transport is not None
    done = install(pippi, part("Ida"))
    assert done.stopped_channels == done.started_channels == ("F1->F2 (x Pippi)",)
    assert [c.other for c in pippi.channels] == ["Ida"]
    transport.send(pippi.channels[0].key, "Pippi", b"{}")
    assert transport.undelivered == 0


def _blocking(release: threading.Event) -> Registry:
    """The example's implementations, each with a stop hook that blocks until ``release``."""
    base = Registry.load(EXAMPLE_IMPL)

    def hooked(impl: Implementation) -> Implementation:
        def stop(*objects: str) -> None:
            release.wait(60)

        return Implementation(impl.name, impl.function, impl.precondition, stop)

    return Registry(hooked(base.lookup(n)) for n in base.names())


def test_a_stop_hook_that_blocks_is_abandoned_after_its_budget() -> None:
    """A hook that blocks froze the switch, and the robot, for good.
    Now it has the budget of a call: the switch goes on after it, and the
    functionality's failure is reported (a call ``timeout``, the install's problems)."""
    before, after = _switch()
    release = threading.Event()
    pippi = build(before["Pippi"], _blocking(release))
    pippi.start(pippi.clock(), rate=0.0, budget=0.2)
    done: list[object] = []
    switching = threading.Thread(target=lambda: done.append(install(pippi, after["Pippi"])))
    began = time.monotonic()
    try:
        switching.start()
        switching.join(10)
        took = time.monotonic() - began
        assert done, "the switch is still waiting for the stop hook"
    finally:
        release.set()
        switching.join(10)
    (installed,) = done
    assert isinstance(installed, Installed)
    assert took < 3  # two hooks, 0.2 s each
    assert len(installed.problems) == 2
    assert all(
        "stop hook took longer than its time budget of 0.2 s" in p for p in installed.problems
    )
    assert ("problems", list(installed.problems)) in installed.record()
    failed = [e for e in pippi.events if isinstance(e, Call) and e.status == "timeout"]
    assert sorted(e.name for e in failed) == ["compass", "measure-robot-orient-compass"]
    assert "abandoned" in failed[0].error


def test_a_stop_hook_that_raises_is_reported_as_a_failed_call() -> None:
    before, after = _switch()

    def broken(impl: Implementation) -> Implementation:
        def stop(*objects: str) -> None:
            raise OSError("motor controller unplugged")

        return Implementation(impl.name, impl.function, impl.precondition, stop)

    base = Registry.load(EXAMPLE_IMPL)
    pippi = build(before["Pippi"], Registry(broken(base.lookup(n)) for n in base.names()))
    pippi.start(pippi.clock(), rate=0.0)
    installed = install(pippi, after["Pippi"])
    assert len(installed.problems) == 2
    failed = [e for e in pippi.events if isinstance(e, Call) and e.status == "error"]
    assert len(failed) == 2
    assert (
        "its stop hook failed: the implementation raised OSError: motor controller unplugged"
        in (failed[0].error)
    )
