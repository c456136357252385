"""Coordination taken over and fenced (cfgplan.reconfigure.succession, 5.5): the
order of succession, the epochs' generations on the wire, a robot's fencing
and a coordinator that steps down. The processes over Zenoh:
test_network_takeover.py."""

from __future__ import annotations

import json
import time

import pytest

from cfgplan.problem import load
from cfgplan.reconfigure.succession import succession_of
from cfgplan.runtime.events import Adaptation, Event
from cfgplan.runtime.protocol import (
    Commit,
    ProtocolError,
    Ready,
    Rival,
    encode,
    generation,
    new_epoch,
    read_to_coordinator,
    read_to_robot,
)
from cfgplan.runtime.succession import Succession
from tests.backends.support import DOMAINS
from tests.reconfigure.test_network_switch import _wall
from tests.runtime.test_member import _member, _message

SEQUENCE = (
    DOMAINS / "cross-door/domain-steps.lisp",
    DOMAINS / "cross-door/state-6.2.2-sequence.lisp",
)


def test_the_order_of_succession_is_the_robots_the_remaining_goals_name() -> None:
    """6.2.2 as a sequence: Pippi crosses, then Emil. While Pippi's crossing
    is served she coordinates and Emil is next; once it is done, only Emil's
    goal remains, and nobody comes after him. Robots that may not coordinate
    (with keys, society.json says which) are left out."""
    problem = load(*SEQUENCE)
    agents = problem.task.agents
    assert succession_of(problem.goal_calls, agents).orders == (("Pippi", "Emil"), ("Emil",))
    only = succession_of(problem.goal_calls, agents, may={"Emil"})
    assert only.orders == (("Emil",), ("Emil",))
    order = Succession((("Pippi", "Emil", "Rasmus"),))
    assert order.successor(0, {"Emil", "Rasmus"}, gone="Pippi") == "Emil"
    assert order.successor(5, {"Rasmus"}, gone="Pippi") == "Rasmus"  # past the end: the last
    assert order.successor(0, set(), gone="Pippi") is None
    steps = Succession((("Pippi", "Emil"), ("Emil",)))
    assert steps.successor(1, {"Pippi", "Emil"}, gone="Pippi") == "Emil"
    # Emil, coordinating his own step, gone: Pippi, whom an earlier goal
    # names, coordinates until he is back (started again, he only follows)
    assert steps.successor(1, {"Pippi"}, gone="Emil") == "Pippi"


def test_an_epoch_counts_its_generation_and_a_commit_says_its_step() -> None:
    assert generation(new_epoch(3)) == 3 and new_epoch(3).startswith("3.")
    assert generation("9f2c0a1b2c3d4e5f") == 0  # a run without one counts none
    assert generation("1234567890123456.x") == 0  # more than 15 digits: none
    commit = Commit(4, "Emil", "2.ab", None, 1)
    assert read_to_robot(encode(commit)) == commit
    assert b"step" not in encode(Commit(4, "Emil", "2.ab"))  # step 0: not written
    rival = Rival("Pippi", "1.cd", "Emil", "2.ab")
    assert read_to_coordinator(encode(rival)) == rival
    bad = {"op": "commit", "id": 4, "from": "Emil", "epoch": "2.ab", "step": -1}
    with pytest.raises(ProtocolError, match="step is -1, not a step of the sequence"):
        read_to_robot(json.dumps(bad).encode())


def test_a_robot_fences_off_older_runs_and_follows_a_later_one_only_from_the_next() -> None:
    """Emil follows Pippi's run of generation 1. With the order Pippi, Emil,
    once her token goes he is next: he is due to take over. With the order
    Pippi, Rasmus, Emil, Rasmus is: a later run from anyone else is not
    obeyed, Rasmus's is followed; from then on a message of Pippi's run
    (she is let go) is fenced off, though her token is back, and she is told
    which run Emil follows."""
    _, member, network, own = _member()
    member.succession = Succession((("Pippi", "Emil"),), after=0.0)
    member.receive(_message("commit", 1, own, epoch="1.aa"))
    assert not member.takeover_due()  # Pippi is alive
    network.presence("Pippi", False)
    time.sleep(0.001)
    assert member.takeover_due()  # Emil is next: he takes over
    member.succession = Succession((("Pippi", "Rasmus", "Emil"),), after=0.0)
    network.alive = {"Rasmus"}  # type: ignore[attr-defined]
    assert not member.takeover_due()  # Rasmus is next
    network.sent.clear()
    member.receive(_message("commit", 0, own, epoch="2.bb").replace(b'"Pippi"', b'"Mallory"'))
    assert member.epoch == "1.aa"  # not next: fenced off
    member.receive(_message("commit", 0, own, epoch="2.cc").replace(b'"Pippi"', b'"Rasmus"'))
    assert (member.epoch, member.leader, member.current) == ("2.cc", "Rasmus", 0)
    network.presence("Pippi", True)
    network.sent.clear()
    member.receive(_message("prepare", 1, own, epoch="1.aa"))
    assert member.pending == {}
    rival = {"type": "rival", "robot": "Emil", "epoch": "1.aa", "leader": "Rasmus", "over": "2.cc"}
    assert [m for _, m in network.sent] == [rival]


def test_a_robot_follows_its_own_coordinator_into_a_later_generation() -> None:
    """A coordinator told of a later run whose robot is gone counts a
    generation beyond it: the robots that follow it, alive, follow it there
    (before, they took it for a second coordinator and refused it)."""
    _, member, network, own = _member()
    member.succession = Succession((("Pippi", "Emil"),))
    member.receive(_message("commit", 1, own, epoch="1.aa"))
    member.receive(_message("commit", 1, own, epoch="3.aa"))
    assert (member.epoch, member.leader, member.current) == ("3.aa", "Pippi", 1)
    assert [m for _, m in network.sent if m["type"] == "rival"] == []


def _steps(events: list[Event]) -> list[dict[str, object]]:
    return [dict(e.info) for e in events if isinstance(e, Adaptation) and e.what == "step-down"]


def test_a_coordinator_steps_down_only_for_the_robot_next_in_the_order_alive() -> None:
    """Pippi coordinates build-wall as run 1; the order is Pippi, Emil, Rasmus.
    Emil's own word that he runs a later run (he took over while she stood
    still) makes her step down and follow him, once (his greeting and his
    rival may come in one pass); a helper's word alone does not (with its
    own key it could make her follow a robot that coordinates nothing); a
    later run of Rasmus (alive, but not next) is not believed; a later run
    of a robot gone — still gone a lease later — makes her count a
    generation beyond it."""
    adaptive, network, clock, events = _wall({"Pippi", "Emil", "Rasmus"})
    adaptive.deployer.member.robot.record = events.append  # type: ignore[method-assign, assignment]
    adaptive.deployer.epoch = "1.aa"
    adaptive.succession = Succession((("Pippi", "Emil", "Rasmus"),))
    adaptive.coordinators = frozenset({"Pippi", "Emil", "Rasmus"})
    adaptive.receive(encode(Rival("Emil", "1.aa", "Rasmus", "2.rr")), "Emil")
    assert adaptive.superseded is None and _steps(events) == []
    network.alive.discard("Emil")
    adaptive.later("Emil", "2.ee")  # Emil is gone: weighed for a lease first
    adaptive.between(1, 0.05)
    assert adaptive.superseded is None and adaptive.deployer.epoch == "1.aa"
    clock.now += network.lease
    adaptive.between(2, 0.1)  # still gone: this coordinator counts beyond him
    assert adaptive.superseded is None and generation(adaptive.deployer.epoch) == 3
    network.alive.add("Emil")
    adaptive.receive(encode(Rival("Rasmus", adaptive.deployer.epoch, "Emil", "4.ee")), "Rasmus")
    assert adaptive.superseded is None  # a helper's word: Emil's own is awaited
    adaptive.later("Emil", "4.ee")  # his greeting reached Pippi's robot
    assert adaptive.superseded == ("Emil", "4.ee")
    # his rival in the same pass: decided already, one step down
    adaptive.receive(encode(Rival("Emil", adaptive.deployer.epoch, "Emil", "4.ee")), "Emil")
    (down,) = _steps(events)
    assert (down["leader"], down["epoch"]) == ("Emil", "4.ee")
    adaptive.receive(encode(Ready("Emil", "a1a1a1a1a1a1a1a1")), "Emil")  # his process
    adaptive.retire()  # it follows Emil now: what reaches the coordinator it was is not read
    network.sent.clear()
    adaptive.process("Emil", "a1a1a1a1a1a1a1a1", True)
    adaptive.process("Emil", "b2b2b2b2b2b2b2b2", True)  # no duplicate from a run fenced off
    adaptive.receive(encode(Ready("Rasmus", "c3c3c3c3c3c3c3c3")), "Rasmus")
    assert network.sent == []


def test_a_coordinator_let_go_steps_down_for_a_successor_whose_token_is_not_back_yet() -> None:
    """Pippi, frozen past the lease, is let go: her session lost Emil's token
    and takes it back only as it catches up, while she reads Emil's greeting
    of his run 2, which waited meanwhile. His token back within the lease,
    she steps down and follows him; she counts no generation beyond him.
    Before, she took him for gone at once, went on as run 3, and he stepped
    down for her: the society went back to the coordinator that froze."""
    adaptive, network, clock, events = _wall({"Pippi", "Emil"})
    adaptive.deployer.member.robot.record = events.append  # type: ignore[method-assign, assignment]
    adaptive.deployer.epoch = "1.aa"
    adaptive.succession = Succession((("Pippi", "Emil"),))
    adaptive.coordinators = frozenset({"Pippi", "Emil"})
    network.alive.discard("Emil")
    adaptive.later("Emil", "2.ee")  # his greeting, read before his token is back
    adaptive.between(1, 0.05)
    assert adaptive.superseded is None and adaptive.deployer.epoch == "1.aa"
    clock.now += network.lease / 2
    network.alive.add("Emil")
    adaptive.between(2, 0.1)
    assert adaptive.superseded == ("Emil", "2.ee") and adaptive.deployer.epoch == "1.aa"
    (down,) = _steps(events)
    assert (down["leader"], down["epoch"], down["was"]) == ("Emil", "2.ee", "1.aa")
    said = adaptive.deployer.member.errors  # type: ignore[attr-defined]
    assert not [e for e in said if "later run" in e], said
