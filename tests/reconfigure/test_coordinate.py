"""The coordinator: detections in, switches out (5.5); staleness blamed upstream only.

A fake deployer records the parts it is given and says "done" at once; the
clock is stepped by hand, so the settling of stale suspicions is exact.
"""

from __future__ import annotations

import time

from cfgplan.configuration.model import Configuration
from cfgplan.notation import call_text
from cfgplan.planner import plan
from cfgplan.problem import load
from cfgplan.reconfigure.coordinate import Coordinator, Done
from cfgplan.reconfigure.decision import Decision
from cfgplan.reconfigure.policy import Reconfigurator
from cfgplan.reconfigure.suspect import upstream
from cfgplan.runtime.events import Adaptation, Event
from cfgplan.runtime.monitor import Detection
from cfgplan.runtime.part import Part
from tests.backends.support import DOMAINS

STEP2 = (DOMAINS / "cross-door/domain.lisp", DOMAINS / "cross-door/state-6.2.2-step2.lisp")


class Deployer:
    def __init__(self) -> None:
        self.deployed: list[tuple[Decision, dict[str, Part]]] = []
        self.later: list[Done] = []
        self.hold = False

    def deploy(
        self, decision: Decision, parts: dict[str, Part], done: Done, failed: object
    ) -> None:
        self.deployed.append((decision, parts))
        if self.hold:
            self.later.append(done)
        else:
            done()


class Clock:
    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


def _coordinator() -> tuple[Coordinator, Deployer, Clock, list[Event], Configuration]:
    problem = load(*STEP2)
    configs, _ = plan(problem.task, problem.goal_call)
    r = Reconfigurator(problem.task, problem.domain, problem.goal_call, configs[0])
    events: list[Event] = []
    deployer, clock = Deployer(), Clock()
    return (
        Coordinator(r, events.append, "Emil", deployer, clock),
        deployer,
        clock,
        events,
        configs[0],
    )


def _label(config: Configuration, name: str, robot: str) -> str:
    return next(f.label for f in config.functionalities if f.name == name and f.robot == robot)


def _stale(label: str, robot: str, channel: str, kind: str = "stale") -> Detection:
    return Detection(kind, "Pippi", 1.0, label=label, other=robot, detail=channel, limit=0.3)  # type: ignore[arg-type]


def test_a_failure_is_recorded_switched_and_timed() -> None:
    coordinator, deployer, _, events, _ = _coordinator()
    coordinator.handle(
        Detection("failure", "Emil", 0.0, instance=("compass", "Emil"), label="F10", how="injected")
    )
    ((decision, parts),) = deployer.deployed
    assert decision.config is not None and decision.config.cost == 47
    assert sorted(parts) == ["Emil", "Pippi"]
    kinds = [e.kind for e in events]
    assert kinds == ["failure", "switch"]
    failure, switch = events
    assert isinstance(failure, Adaptation) and isinstance(switch, Adaptation)
    assert failure.field("resource") == "compass(Emil)" and failure.field("how") == "injected"
    assert failure.field("withdrawn") == ["(compass Emil)"]
    assert (switch.field("from_cost"), switch.field("to_cost")) == (44, 47)
    assert switch.field("latency") > 1.0e6  # type: ignore[operator]  # from t=0: the epoch
    coordinator.handle(Detection("failure", "Emil", 1.0, instance=("compass", "Emil")))
    assert len(deployer.deployed) == 1  # known already


def test_the_sender_of_a_stale_input_is_blamed_after_the_limit() -> None:
    coordinator, deployer, clock, events, config = _coordinator()
    compass = _label(config, "compass", "Emil")
    coordinator.handle(_stale(compass, "Emil", "compass->orient"))
    clock.now += 0.2
    coordinator.tick()
    assert deployer.deployed == []  # not yet settled
    clock.now += 0.2
    coordinator.tick()
    ((decision, _),) = deployer.deployed
    assert decision.cause == "compass(Emil) failed"
    failure = next(e for e in events if e.kind == "failure")
    assert isinstance(failure, Adaptation) and failure.field("how") == "stale"


def test_fresh_data_withdraws_the_suspicion() -> None:
    coordinator, deployer, clock, _, config = _coordinator()
    compass = _label(config, "compass", "Emil")
    coordinator.handle(_stale(compass, "Emil", "c"))
    clock.now += 0.2
    coordinator.handle(_stale(compass, "Emil", "c", "fresh"))
    clock.now += 1.0
    coordinator.tick()
    assert deployer.deployed == []


def test_staleness_downstream_of_a_suspect_is_not_blamed() -> None:
    """Emil's compass falls silent: Pippi's measure-robot-orient-compass goes
    stale on it, and then transform-info and cross-door starve. Only the
    compass is blamed."""
    coordinator, deployer, clock, events, config = _coordinator()
    transform = _label(config, "transform-info", "Pippi")
    orient = _label(config, "measure-robot-orient-compass", "Pippi")
    compass = _label(config, "compass", "Emil")
    assert {compass, orient} <= upstream(config, transform)
    coordinator.handle(_stale(transform, "Pippi", "t->x"))  # cross-door's input, first
    coordinator.handle(_stale(orient, "Pippi", "o->t"))
    clock.now += 0.25
    coordinator.handle(_stale(compass, "Emil", "c->o"))
    clock.now += 0.1
    coordinator.tick()
    assert deployer.deployed == []  # the compass's suspicion is not ripe; nothing else is a root
    clock.now += 0.3
    coordinator.tick()
    ((decision, _),) = deployer.deployed
    assert decision.cause == "compass(Emil) failed"
    assert [
        e.field("resource") for e in events if isinstance(e, Adaptation) and e.kind == "failure"
    ] == ["compass(Emil)"]


def test_detections_wait_while_a_switch_is_deployed() -> None:
    coordinator, deployer, _, events, _ = _coordinator()
    deployer.hold = True
    coordinator.handle(Detection("failure", "Emil", 0.0, instance=("compass", "Emil")))
    coordinator.handle(Detection("lost", "Emil", 0.0, other="Pippi"))
    assert len(deployer.deployed) == 1 and [e.kind for e in events] == ["failure"]
    coordinator.tick()
    assert len(deployer.deployed) == 1  # still deploying
    deployer.later.pop()()
    assert [e.kind for e in events] == ["failure", "switch"]
    deployer.hold = False
    coordinator.tick()
    assert [e.kind for e in events] == ["failure", "switch", "failure", "no-configuration"]
    assert coordinator.stopped


def test_an_achieved_task_ends_the_run() -> None:
    coordinator, deployer, _, events, _ = _coordinator()
    coordinator.handle(
        Detection("achieved", "Emil", 0.0, instance=("cross-door", "Emil", "Door1"), label="F3")
    )
    assert coordinator.finished == "achieved"
    assert [e.kind for e in events] == ["achieved"]
    ((decision, parts),) = deployer.deployed
    assert decision.action == "stop" and all(p.calls == () for p in parts.values())


def test_a_task_reported_accomplished_twice_ends_once() -> None:
    """Two reports in one pass (both robots' actions, or one action in two
    cycles before the stop is deployed) end the run once; a report from an
    instance that is not running is ignored."""
    coordinator, deployer, _, events, config = _coordinator()
    label = _label(config, "cross-door", "Emil")
    stranger = Detection(
        "achieved", "Pippi", 0.0, instance=("cross-door", "Pippi", "Door1"), label=label
    )
    coordinator.handle(stranger)
    assert coordinator.finished is None and events == [] and deployer.deployed == []
    done = Detection("achieved", "Emil", 0.0, instance=("cross-door", "Emil", "Door1"), label=label)
    coordinator.handle(done)
    coordinator.handle(done)
    assert coordinator.finished == "achieved"
    assert [e.kind for e in events] == ["achieved"]
    assert len(deployer.deployed) == 1


def _twice() -> tuple[Coordinator, Reconfigurator, Deployer, list[Event], Configuration]:
    """A sequence of two steps, the same crossing twice: its coordinator,
    reconfigurator, deployer, events and the first step's configuration."""
    problem = load(*STEP2)
    configs, _ = plan(problem.task, problem.goal_call)
    goal = problem.goal_call
    r = Reconfigurator(problem.task, problem.domain, goal, configs[0], goals=(goal,))
    events: list[Event] = []
    deployer = Deployer()
    return Coordinator(r, events.append, "Emil", deployer, Clock()), r, deployer, events, configs[0]


def test_a_second_report_does_not_skip_a_step_of_a_sequence() -> None:
    """A sequence of two steps (the same crossing twice): the first step's
    task reported twice in one pass (made before the switch) moves to the
    second step once; a report made after the switch ends the second step."""
    coordinator, r, _, events, first = _twice()
    label = _label(first, "cross-door", "Emil")
    done = Detection("achieved", "Emil", 0.0, instance=("cross-door", "Emil", "Door1"), label=label)
    coordinator.handle(done)
    coordinator.handle(done)
    assert coordinator.finished is None  # the second step runs
    assert r.goals == () and r.running is not None
    assert [e.kind for e in events].count("achieved") == 1
    second = r.running
    assert any(f.label == label for f in second.functionalities)  # the same crossing again
    later = Detection("achieved", "Emil", time.time() + 1, instance=done.instance, label=label)
    coordinator.handle(later)  # reported once the second step runs: it ends that step
    assert coordinator.finished == "achieved"
    assert [e.kind for e in events].count("achieved") == 2


def test_a_robots_report_is_placed_by_the_configuration_it_ran_not_its_clock() -> None:
    """Robots' clocks may differ. After the switch to the sequence's second
    step, a report from a robot whose clock is an hour behind, made under the
    second step's configuration, ends that step; one from a clock an hour
    ahead, made under the first step's, is not about the second step."""
    coordinator, r, deployer, events, first = _twice()
    label = _label(first, "cross-door", "Emil")
    instance = ("cross-door", "Emil", "Door1")
    coordinator.handle(Detection("achieved", "Emil", 0.0, instance=instance, label=label))
    ((second_step, _),) = deployer.deployed
    assert second_step.previous is first and r.running is second_step.config
    assert second_step.id > 0
    ahead = time.time() + 3600
    old = Detection("achieved", "Emil", ahead, instance=instance, label=label, config=0)
    coordinator.handle(old)
    assert coordinator.finished is None
    behind = time.time() - 3600
    now = Detection(
        "achieved", "Emil", behind, instance=instance, label=label, config=second_step.id
    )
    coordinator.handle(now)
    assert coordinator.finished == "achieved"
    assert [e.kind for e in events].count("achieved") == 2


def test_installing_a_configuration_keeps_what_is_shared() -> None:
    """The operation sequences of configurations (7.3) reuse: install X now."""
    coordinator, deployer, _, events, first = _coordinator()
    problem = load(*STEP2)
    configs, _ = plan(problem.task, problem.goal_call, limit=2)
    coordinator.install(configs[1], "next step")
    ((decision, _),) = deployer.deployed
    assert decision.config is not None and decision.config.cost == 47
    assert decision.change is not None and len(decision.change.kept) == 5
    (switch,) = events
    assert isinstance(switch, Adaptation) and switch.field("cause") == "next step"
    coordinator.install(None, "done")
    assert coordinator.stopped and coordinator.reconfigurator.running is None
    assert first.cost == 44


def test_a_robot_seen_again_brings_back_what_its_silence_blamed() -> None:
    """Pippi freezes: her output to Emil goes stale and, before her lease runs
    out, the computation on her is blamed (a silent robot looks like
    a silent computation at first); every configuration of step 2 needs her,
    so the society stops. Her loss is then noticed and, once she is seen
    again, what her silence blamed recovers with her: the society runs again
    (before, transform-info stayed failed and it stopped for good)."""
    coordinator, deployer, clock, events, config = _coordinator()
    transform = next(
        f for f in config.functionalities if f.name == "transform-info" and f.robot == "Pippi"
    )
    coordinator.handle(_stale(transform.label, "Pippi", "transform->cross"))
    clock.now += 0.5
    coordinator.tick()
    ((stopped, _),) = deployer.deployed
    assert stopped.config is None  # nothing admissible without transform-info(Pippi ...)
    coordinator.handle(Detection("lost", "Emil", 2.0, other="Pippi"))
    coordinator.handle(Detection("seen", "Emil", 3.0, other="Pippi"))
    decision, _ = deployer.deployed[-1]
    assert decision.config is not None and decision.config.cost == 44
    recovered = [e for e in events if e.kind == "recovery"]
    assert [e.field("resource") for e in recovered if isinstance(e, Adaptation)] == [
        "Pippi",
        call_text(transform.key),
    ]


def test_what_staleness_blamed_is_tried_again_after_its_hold_doubling() -> None:
    """Pippi's output to Emil stalls without Pippi being lost (a freeze shorter
    than her lease, a stalled link): the computation on her is blamed and the
    society stops. After the hold (1 s) it is tried again by itself, no
    scripted recover: the society runs 44 again. Blamed a second time, it
    waits twice as long."""
    coordinator, deployer, clock, events, config = _coordinator()

    def stall(running: Configuration) -> None:
        transform = next(
            f for f in running.functionalities if f.name == "transform-info" and f.robot == "Pippi"
        )
        coordinator.handle(_stale(transform.label, "Pippi", "transform->cross"))
        clock.now += 0.5
        coordinator.tick()

    stall(config)
    assert deployer.deployed[-1][0].config is None  # stopped
    clock.now += 0.9
    coordinator.tick()
    assert len(deployer.deployed) == 1  # within the hold: still out
    clock.now += 0.2
    coordinator.tick()
    decision, _ = deployer.deployed[-1]
    assert decision.config is not None and decision.config.cost == 44
    retried = [e for e in events if e.kind == "recovery" and isinstance(e, Adaptation)]
    assert [(e.field("resource"), e.field("how")) for e in retried] == [
        ("transform-info(Pippi, Emil, Door1)", "retry")
    ]
    stall(decision.config)  # relabelled by the switch
    assert deployer.deployed[-1][0].config is None
    clock.now += 1.1
    coordinator.tick()
    assert deployer.deployed[-1][0].config is None  # the hold doubled: 2 s now
    clock.now += 1.0
    coordinator.tick()
    assert deployer.deployed[-1][0].config is not None


def test_a_lost_robot_is_not_tried_again_before_it_is_seen() -> None:
    """The robot whose data stopped is lost: its hold passing is no evidence."""
    coordinator, deployer, clock, _, config = _coordinator()
    transform = next(
        f for f in config.functionalities if f.name == "transform-info" and f.robot == "Pippi"
    )
    coordinator.handle(_stale(transform.label, "Pippi", "transform->cross"))
    clock.now += 0.5
    coordinator.tick()
    coordinator.handle(Detection("lost", "Emil", 2.0, other="Pippi"))
    clock.now += 5.0
    coordinator.tick()
    assert all(decision.config is None for decision, _ in deployer.deployed)
