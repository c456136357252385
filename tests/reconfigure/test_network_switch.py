"""The coordinator's side of the two-phase switch (5.5, cfgplan.reconfigure.network)
when robots misbehave: a malformed message, a refusal after the others
committed, a robot that was not up during the switch, two robots silent in
one switch. On the fake network and stepped clock of test_network_retry."""

from __future__ import annotations

import json
import time
from types import SimpleNamespace

from cfgplan.planner import plan
from cfgplan.problem import load
from cfgplan.reconfigure.coordinate import Coordinator, Done, Failed
from cfgplan.reconfigure.decision import Decision
from cfgplan.reconfigure.fallbacks import Resource
from cfgplan.reconfigure.network import SWITCH_TIMEOUT, NetworkAdaptive, NetworkDeployer
from cfgplan.reconfigure.policy import Reconfigurator
from cfgplan.runtime.events import Event
from cfgplan.runtime.monitor import Detection, Monitor
from cfgplan.runtime.part import part_to_json
from tests.backends.support import DOMAINS
from tests.reconfigure.test_coordinate import Clock
from tests.reconfigure.test_network_retry import Idle, Me, Network, _society, _wait, _what

WALL = (DOMAINS / "build-wall/domain.lisp", DOMAINS / "build-wall/state-6.4.lisp")
COMPASS = Detection("failure", "Emil", 1.0, instance=("compass", "Emil"), how="injected")


def _wall(alive: set[str]) -> tuple[NetworkAdaptive, Network, Clock, list[Event]]:
    """Build-wall (6.4), coordinated by Pippi, running 53 (Pippi and Emil)."""
    problem = load(*WALL)
    configs, _ = plan(problem.task, problem.goal_call)
    reconfigurator = Reconfigurator(problem.task, problem.domain, problem.goal_call, configs[0])
    network, clock, events = Network(alive=alive), Clock(), []
    me = Me(robot=Me._Robot("Pippi"))
    deployer = NetworkDeployer(
        network,  # type: ignore[arg-type]
        me,  # type: ignore[arg-type]
        clock=clock,
        parts=reconfigurator.parts(),  # as coordinate() starts it
    )
    coordinator = Coordinator(reconfigurator, events.append, "Pippi", deployer, clock)
    adaptive = NetworkAdaptive(coordinator, deployer, Monitor(), Idle())  # type: ignore[arg-type]
    return adaptive, network, clock, events


def test_malformed_answers_and_reports_are_ignored_even_during_a_switch() -> None:
    """An ack whose id is ``1e999`` raised OverflowError, and a report with
    ``"config": "x"`` queued during a switch raised TypeError from the
    backlog, both out of the coordinator's loop."""
    adaptive, _network, _clock, events = _society()
    adaptive.take(COMPASS)
    switch = adaptive.deployer.switch
    assert switch is not None
    number = switch.decision.id
    adaptive.receive(b'{"type":"ack","robot":"Pippi","id":1e999,"phase":"ready"}')
    bad = {"kind": "achieved", "robot": "Pippi", "t": 1.0, "label": "F1", "config": "x"}
    adaptive.receive(json.dumps({"type": "report", "robot": "Pippi", "detection": bad}).encode())
    assert adaptive.coordinator._backlog == []
    for phase in ("ready", "installed"):
        ack = {"type": "ack", "robot": "Pippi", "id": number, "phase": phase}
        adaptive.receive(json.dumps({**ack, "epoch": "another coordinator's"}).encode())
        adaptive.receive(json.dumps({**ack, "epoch": adaptive.deployer.epoch}).encode())
    adaptive.between(0, 0.0)
    running = adaptive.coordinator.reconfigurator.running
    assert adaptive.deployer.switch is None and running is not None and running.cost == 47
    assert ("switch", "") in _what(events)


def test_a_refusal_after_the_commit_rolls_nothing_back() -> None:
    """By the commit the coordinator runs the new configuration: a robot
    that refuses it then (it lost what it prepared, started again since) is
    sent its part itself; refused again, it is taken as lost and the
    society planned again without it, with no abort."""
    adaptive, network, _clock, events = _society()
    adaptive.take(COMPASS)
    switch = adaptive.deployer.switch
    assert switch is not None
    number = switch.decision.id
    adaptive.deployer.acked("Pippi", number, "ready", "")
    assert adaptive.deployer.member.installed == [number]  # type: ignore[attr-defined]
    adaptive.deployer.acked("Pippi", number, "refused", "never prepared here")
    resent = network.to("Pippi", "commit")[-1]
    assert resent["id"] == number and "part" in resent
    assert "abort" not in [what for what, _ in _what(events)]
    adaptive.deployer.acked("Pippi", number, "refused", "cannot run it")
    assert adaptive.deployer.switch is None  # done for the others
    adaptive.between(0, 0.0)
    assert "abort" not in [what for what, _ in _what(events)]
    assert ("failure", "refused") in _what(events)
    assert "Pippi" in adaptive.coordinator.reconfigurator.situation.lost


def test_a_robot_not_up_during_a_switch_is_sent_its_new_part_when_it_appears() -> None:
    """Pippi's process is not up when Emil's compass fails (47 needs her):
    when she appears she gets her part of 47 under its id, not her part of
    44 (she ran half of another configuration)."""
    adaptive, network, _clock, _events = _society()
    reconfigurator = adaptive.coordinator.reconfigurator
    adaptive.deployer.parts = reconfigurator.parts()  # as coordinate() starts it: 44
    network.alive = {"Emil"}
    adaptive.take(COMPASS)
    running = reconfigurator.running
    assert running is not None and running.cost == 47 and adaptive.deployer.switch is None
    network.alive.add("Pippi")
    adaptive.take(Detection("seen", "Emil", time.time(), other="Pippi"))
    sent = network.to("Pippi", "commit")[-1]
    assert sent["id"] == adaptive.deployer.current > 0
    assert sent["part"] == part_to_json(reconfigurator.parts()["Pippi"])


def test_two_robots_silent_in_one_switch_are_lost_in_one_decision() -> None:
    """Emil's laser fails (6.4: 53 -> 66 needs Rasmus); Emil and Rasmus do
    not answer the prepare: both are lost in one decision (here: nothing is
    admissible with Pippi alone), noted one by one."""
    adaptive, network, clock, events = _wall({"Pippi", "Emil", "Rasmus"})
    reconfigurator = adaptive.coordinator.reconfigurator
    adaptive.take(Detection("failure", "Emil", 1.0, instance=("laser", "Emil"), how="injected"))
    assert network.to("Emil", "prepare") and network.to("Rasmus", "prepare")
    decided = reconfigurator.id
    _wait(adaptive, clock, SWITCH_TIMEOUT + 0.1)
    assert {"Emil", "Rasmus"} <= set(reconfigurator.situation.lost)
    assert reconfigurator.id == decided + 1 and reconfigurator.running is None
    failures = [e for e in events if getattr(e, "what", "") == "failure"]
    assert [dict(f.info)["resource"] for f in failures[-2:]] == ["Emil", "Rasmus"]


class _Deployer:
    """Deploys nothing: counts the switches in flight; the first one's
    robots Rasmus and Robby stay silent."""

    def __init__(self) -> None:
        self.in_flight: list[int] = []

    def deploy(self, decision: Decision, parts: object, done: Done, failed: Failed) -> None:
        self.in_flight.append(decision.id)
        if decision.id == 1:
            self.in_flight.remove(1)
            failed(["Rasmus", "Robby"], "silent")


class _Reconfigurator:
    """Every loss of a robot calls for a switch (one whose robots are all
    still there would, on a society larger than the bundled ones)."""

    def __init__(self) -> None:
        self.situation = SimpleNamespace(lost=set(), failed=set())
        self.running, self.id, self.goals = "C0", 1, ()

    def failed(
        self, resource: Resource, cause: str = "", together: tuple[Resource, ...] = ()
    ) -> Decision:
        self.situation.lost.update(r.robot for r in (resource, *together))
        self.id += 1
        previous, self.running = self.running, f"C{self.id}"
        return Decision("switch", self.id, None, previous, None)  # type: ignore[arg-type]

    def parts(self, previous: object = None) -> dict[str, object]:
        return {}

    def rollback(self, previous: object) -> None:
        self.running = previous


def test_robots_silent_in_one_switch_start_one_switch_not_one_each() -> None:
    """Before, the abort's callback took the robots one by one, and each
    started a switch while the one before was still in flight."""
    deployer, reconfigurator = _Deployer(), _Reconfigurator()
    coordinator = Coordinator(reconfigurator, lambda e: None, "Vacu", deployer)  # type: ignore[arg-type]
    first = Decision("switch", 1, None, "C0", None)  # type: ignore[arg-type]
    coordinator._apply(first, Detection("failure", "Vacu", 0.0))
    assert deployer.in_flight == [2] and reconfigurator.situation.lost == {"Rasmus", "Robby"}
