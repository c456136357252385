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
from cfgplan.reconfigure.deployer import NOT_RUNNING
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
from cfgplan.runtime.part import CallSpec, Part
from cfgplan.runtime.protocol import Phase, Ready, encode
from tests.reconfigure.test_coordinate import STEP2, Clock


@dataclass
class Network:
    society: str = "retry-test"
    alive: set[str] = field(default_factory=lambda: {"Emil", "Pippi"})
    sent: list[tuple[str, dict[str, object]]] = field(default_factory=list)
    dropped: int = 0  # messages past the backlog (none here)
    lease: float = 1.0  # seconds (the session's)
    options: SimpleNamespace = field(default_factory=lambda: SimpleNamespace(backlog=10_000))

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
        released: bool = False

        def release(self) -> None:  # the run is over: the others leave, no loss
            self.released = True

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
        adaptive.receive(encode(Ready(robot)), robot)
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
    alive — with her empty part in the commit, not waiting for her answer
    (she has nothing to prepare). Alive all the while, she is tried again
    RETRY seconds later, answers this time, and the society switches to the
    configuration with her (6.2.2 step 2: 47)."""
    adaptive, network, clock, events = _society()
    compass = Detection("failure", "Emil", 1.0, instance=("compass", "Emil"), how="injected")
    adaptive.take(compass)
    assert len(network.to("Pippi", "prepare")) == 1
    _wait(adaptive, clock, SWITCH_TIMEOUT + 0.1)
    assert _what(events)[-3:] == [
        ("abort", "silent"),
        ("failure", "silent"),
        ("no-configuration", ""),
    ]
    assert "Pippi" in adaptive.coordinator.reconfigurator.situation.lost
    assert len(network.to("Pippi", "prepare")) == 1  # the stop is not prepared
    stop = network.to("Pippi", "commit")[-1]
    assert stop["part"] == {"robot": "Pippi", "channels": [], "calls": []}
    assert adaptive.deployer.switch is None  # and not waited for
    _wait(adaptive, clock, RETRY - 0.2)  # not yet
    assert ("recovery", "retry") not in _what(events)
    assert len(network.to("Pippi", "prepare")) == 1
    _wait(adaptive, clock, 0.2)
    assert _what(events)[-1] == ("recovery", "retry")
    assert "Pippi" not in adaptive.coordinator.reconfigurator.situation.lost
    prepare = network.to("Pippi", "prepare")[-1]
    assert len(network.to("Pippi", "prepare")) == 2
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
        camera = CallSpec("F1", "camera", ("Pippi",), (), ())  # a part to prepare
        parts = {"Pippi": Part("Pippi", (), (camera,))}
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


def _deployer() -> tuple[NetworkDeployer, Network, Clock]:
    network, clock = Network(alive={"Emil", "Pippi", "Rasmus"}), Clock()
    deployer = NetworkDeployer(network, Me(), clock=clock)  # type: ignore[arg-type]
    for robot in ("Pippi", "Rasmus"):
        deployer.said_ready(robot)
    return deployer, network, clock


def test_a_robot_that_only_leaves_is_not_waited_for() -> None:
    """A switch away from Rasmus (frozen, say): his new part is empty, so he
    is sent no prepare, only the commit carrying his empty part; the switch
    runs once Pippi, who joins, answers — not after the timeout."""
    deployer, network, _clock = _deployer()
    done: list[bool] = []
    camera = CallSpec("F1", "camera", ("Pippi",), (), ())
    parts = {"Pippi": Part("Pippi", (), (camera,)), "Rasmus": Part("Rasmus", (), ())}
    deployer.deploy(SimpleNamespace(id=1), parts, lambda: done.append(True), lambda *_: None)  # type: ignore[arg-type]
    assert [m["op"] for m in network.to("Pippi", "prepare")] == ["prepare"]
    assert network.to("Rasmus", "prepare") == []
    deployer.acked("Pippi", 1, Phase.READY, "")
    (leave,) = network.to("Rasmus", "commit")
    assert leave["part"] == {"robot": "Rasmus", "channels": [], "calls": []}
    assert network.to("Pippi", "commit")[0].get("part") is None  # prepared: no part again
    deployer.acked("Pippi", 1, Phase.INSTALLED, "")
    assert done == [True] and deployer.switch is None


def test_a_robot_gone_in_a_switch_is_not_waited_out() -> None:
    """Liveliness says Pippi went while the switch awaits her: a prepare is
    aborted at once (she is lost), a commit goes on without her."""
    deployer, network, _clock = _deployer()  # the clock never moves
    camera = CallSpec("F1", "camera", ("Pippi",), (), ())
    laser = CallSpec("F2", "laser", ("Rasmus",), (), ())
    parts = {"Pippi": Part("Pippi", (), (camera,)), "Rasmus": Part("Rasmus", (), (laser,))}
    aborted: list[tuple[list[str], str]] = []
    done: list[bool] = []
    fail = lambda robots, why: aborted.append((robots, why))  # noqa: E731
    deployer.deploy(SimpleNamespace(id=1), parts, lambda: done.append(True), fail)  # type: ignore[arg-type]
    network.alive.discard("Pippi")
    deployer.gone("Pippi")
    assert aborted == [(["Pippi"], "lost")] and deployer.switch is None
    deployer.said_ready("Pippi")  # back
    network.alive.add("Pippi")
    deployer.deploy(SimpleNamespace(id=3), parts, lambda: done.append(True), fail)  # type: ignore[arg-type]
    for robot in ("Pippi", "Rasmus"):
        deployer.acked(robot, 3, Phase.READY, "")
    deployer.acked("Rasmus", 3, Phase.INSTALLED, "")
    assert done == [] and deployer.switch is not None
    deployer.gone("Pippi")
    assert done == [True] and deployer.switch is None
    assert aborted == [(["Pippi"], "lost")]


def test_a_robot_of_the_new_configuration_not_running_aborts_the_switch_at_once() -> None:
    """Docking with the ceiling camera declared but its process never started:
    a switch to the configuration with the camera completed at once, nobody
    sent the camera its part, and the dock waited for its data for good. Now
    the switch is aborted before anything is sent and the camera is taken as
    lost (``not running``): the coordinator plans without it until it is seen."""
    deployer, network, _clock = _deployer()
    camera = CallSpec("F1", "camera", ("Cam",), (), ())
    laser = CallSpec("F2", "laser", ("Rasmus",), (), ())
    parts = {"Cam": Part("Cam", (), (camera,)), "Rasmus": Part("Rasmus", (), (laser,))}
    aborted: list[tuple[list[str], str]] = []
    done: list[bool] = []
    fail = lambda robots, why: aborted.append((robots, why))  # noqa: E731
    deployer.deploy(SimpleNamespace(id=1), parts, lambda: done.append(True), fail)  # type: ignore[arg-type]
    assert aborted == [(["Cam"], NOT_RUNNING)] and done == [] and deployer.switch is None
    assert network.to("Rasmus", "prepare") == []  # nothing prepared, only the abort


def test_a_finish_lost_on_the_way_is_told_again_until_the_robot_answers() -> None:
    """Emil's task is accomplished: he tells Pippi to finish. On a loaded
    machine Zenoh drops a message its link's queue cannot take at once, and
    the finish, told once, was lost: Pippi never ended her run, and took over
    once Emil left. Told again ``greet`` seconds later, then twice as long
    each time, while she has not answered and the wait is not over, she ends;
    once she answers she is told no more. A robot that never answers is told
    until the wait is over, and is then said silent."""
    adaptive, network, clock, _ = _society()
    deployer = adaptive.deployer

    def tick(seconds: float) -> None:
        clock.now += seconds
        deployer.tick()

    goal = "do-cross-door(Emil, Door1)"
    deployer.finish(goal)
    (told,) = network.to("Pippi", "finish")
    assert (told["from"], told["goal"]) == ("Emil", goal)
    tick(deployer.greet - 0.01)
    assert len(network.to("Pippi", "finish")) == 1 and deployer.ended() is None
    tick(0.02)
    assert network.to("Pippi", "finish") == [told, told]  # the first one was lost
    deployer.acked("Pippi", int(str(told["id"])), Phase.FINISHED, "")
    assert deployer.ended() == []
    tick(4 * deployer.greet)
    assert len(network.to("Pippi", "finish")) == 2  # answered: told no more

    adaptive, network, clock, _ = _society()
    deployer = adaptive.deployer
    deployer.finish(goal)
    for _ in range(round(SWITCH_TIMEOUT / deployer.greet) + 4):
        tick(deployer.greet)
    assert deployer.ended() == ["Pippi"]
    tries = len(network.to("Pippi", "finish"))
    assert tries == 4, tries  # at 0, 0.25, 0.75 and 1.75 s; none past the 2 s wait


def test_a_prepare_or_a_commit_lost_on_the_way_is_told_again_until_the_robot_answers() -> None:
    """Emil's compass fails: the switch to 47 needs Pippi. Her prepare is lost
    on the way (or her answer is): she is told it again ``greet`` seconds
    later, answers, and the switch commits; the commit is lost in turn: told
    again, she installs it and answers, and the switch runs — not aborted
    for her silence, she is not taken as lost (before, one message lost cost
    the abort, her loss, and a switch to nothing until she was tried again)."""
    adaptive, network, clock, events = _society()
    deployer = adaptive.deployer
    compass = Detection("failure", "Emil", 1.0, instance=("compass", "Emil"), how="injected")
    adaptive.take(compass)
    (prepare,) = network.to("Pippi", "prepare")
    _wait(adaptive, clock, deployer.greet - 0.01)
    assert len(network.to("Pippi", "prepare")) == 1
    _wait(adaptive, clock, 0.02)
    assert network.to("Pippi", "prepare") == [prepare, prepare]
    number = int(str(prepare["id"]))
    deployer.acked("Pippi", number, Phase.READY, "")
    (commit,) = [m for m in network.to("Pippi", "commit") if m["id"] == number]
    _wait(adaptive, clock, deployer.greet + 0.01)
    assert [m for m in network.to("Pippi", "commit") if m["id"] == number] == [commit, commit]
    deployer.acked("Pippi", number, Phase.INSTALLED, "")
    assert deployer.switch is None
    _wait(adaptive, clock, SWITCH_TIMEOUT)
    assert len(network.to("Pippi", "commit")) == 2  # answered: told no more
    assert ("abort", "silent") not in _what(events)
    running = adaptive.coordinator.reconfigurator.running
    assert running is not None and running.cost == 47 and "Pippi" in running.agents
    assert "Pippi" not in adaptive.coordinator.reconfigurator.situation.lost
