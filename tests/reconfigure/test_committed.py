"""What the society committed, told to every robot (cfgplan.reconfigure.committed, 5.5, 7.2):
the ``state`` message read back and bounded, checked against the task where
a successor takes it, kept by each robot from the run it follows, and sent by
the coordinator once nothing is in flight. The processes over Zenoh:
test_takeover_committed.py."""

from __future__ import annotations

import json
import re

import pytest

from cfgplan.problem import load
from cfgplan.reconfigure.committed import situation_of, state_of
from cfgplan.reconfigure.situation import Situation
from cfgplan.runtime.member import Member
from cfgplan.runtime.monitor import Detection, Monitor
from cfgplan.runtime.protocol import MAX_FACTS, MAX_TERMS, ProtocolError, State, encode
from cfgplan.runtime.protocol import read_to_robot as read
from cfgplan.runtime.succession import Succession, candidates
from tests.reconfigure.test_coordinate import STEP2
from tests.reconfigure.test_network_retry import SWITCH_TIMEOUT, _society, _wait
from tests.runtime.test_member import Network, _member, _message

LEARNT = State(
    3,
    "Pippi",
    "1.aa",
    1,
    added=(("in", "Pippi", "Room2"),),
    removed=(("compass", "Emil"), ("in", "Pippi", "Room1")),
    failed=(("camera", "Pippi"),),
    down=(0,),
    reliability=((("camera", "Pippi"), 0.5),),
)


def test_a_state_reads_back_as_written_and_says_nothing_it_need_not() -> None:
    assert read(encode(LEARNT)) == LEARNT
    bare = State(0, "Pippi", "1.aa")
    assert json.loads(encode(bare)) == {"op": "state", "id": 0, "from": "Pippi", "epoch": "1.aa"}
    assert read(encode(bare)) == bare


def _state(**fields: object) -> bytes:
    return json.dumps({"op": "state", "id": 1, "from": "P", "epoch": "1.a", **fields}).encode()


@pytest.mark.parametrize(
    ("payload", "why"),
    [
        (_state(added=[["in", "P", "R"]] * (MAX_FACTS + 1)), f"at most {MAX_FACTS}"),
        (_state(added=[["x"] * (MAX_TERMS + 1)]), f"1 to {MAX_TERMS} names"),
        (_state(removed=[[]]), "is not a fact"),
        (_state(removed=["compass Emil"]), "is not a fact"),
        (_state(failed=[["compass", ""]]), "is not a name"),
        (_state(failed=[["compass", 3]]), "is not a name"),
        (_state(added={"in": "P"}), "not a list"),
        (_state(down=[-1]), "not a medium's index"),
        (_state(down=[True]), "not a medium's index"),
        (_state(reliability=[[["camera", "P"], 0]]), "above 0, at most 1"),
        (_state(reliability=[[["camera", "P"], 1.5]]), "above 0, at most 1"),
        (_state(reliability=[[["camera", "P"], "0.5"]]), "above 0, at most 1"),
        (_state(reliability=[[["camera", "P"]]]), "not [instance, number]"),
        (
            _state(reliability=[[["camera", "P"], 2]]).replace(b"2]]", b"1e999]]"),
            "above 0, at most 1",
        ),
        (_state(step=-1), "not a step of the sequence"),
        (_state().replace(b"}", b', "reliability": [[["c", "P"], NaN]]}'), "not JSON"),
    ],
)
def test_a_state_that_is_none_is_refused_with_why(payload: bytes, why: str) -> None:
    with pytest.raises(ProtocolError, match=re.escape(why)):
        read(payload)


def test_a_situation_too_large_to_tell_is_not_told_in_part() -> None:
    many = Situation(asserted=tuple(("seen", f"R{i}") for i in range(MAX_FACTS + 1)))
    assert state_of(many, 1, "Pippi", "1.aa", 0) is None
    fits = Situation(asserted=many.asserted[:MAX_FACTS], failed=(("camera", "Pippi"),))
    state = state_of(fits, 1, "Pippi", "1.aa", 2)
    assert state is not None and read(encode(state)) == state and state.step == 2


def test_a_successor_takes_what_the_task_knows_and_says_what_it_drops() -> None:
    """A guard fact (which no state can write: forged, it would stop a robot
    or a functionality for good), an instance of no functionality, a medium
    the state does not declare: dropped, each said. A fact both added and
    removed is added, as the coordinator's own update leaves it."""
    task = load(*STEP2).task
    sent = State(
        1,
        "Pippi",
        "1.aa",
        added=(("in", "Emil", "Room2"), (":lost", "Pippi"), ("open", "Door1")),
        removed=(("compass", "Emil"), ("open", "Door1"), (":out-of-service", "camera", "Emil")),
        failed=(("compass", "Pippi"), ("teleport", "Pippi")),
        down=(0,),
        reliability=((("camera", "Emil"), 0.25), (("teleport", "Pippi"), 0.5)),
    )
    situation, dropped = situation_of(sent, task)
    assert situation == Situation(
        failed=(("compass", "Pippi"),),
        asserted=(("in", "Emil", "Room2"), ("open", "Door1")),
        retracted=(("compass", "Emil"),),
        reliability=((("camera", "Emil"), 0.25),),
    )
    assert dropped == (
        "a fact added, (:lost Pippi): no state can write a fact of :lost",
        "a fact removed, (:out-of-service camera Emil): no state can write a fact of "
        ":out-of-service",
        "(teleport Pippi): not an instance of a functionality of the domain",
        "medium 0: the state declares 0 media",
        "(teleport Pippi): not an instance of a functionality of the domain",
    )
    assert situation_of(LEARNT, task)[0].media_down == ()


def test_a_robot_keeps_the_last_state_of_the_run_it_follows() -> None:
    """Emil follows Pippi's run: he keeps her last state (a later one, or one
    of the same id after a change that needed no switch), not an older one;
    a state of a second coordinator, while Pippi is alive, is refused as its
    switches are. The state's step is the society's step."""
    _, member, network, own = _member()
    member.receive(_message("commit", 3, own, epoch="1.aa"))
    member.receive(encode(LEARNT))
    assert member.known == LEARNT and member.step == 1
    member.receive(encode(State(2, "Pippi", "1.aa", 0)))
    assert member.known == LEARNT  # older
    same = State(3, "Pippi", "1.aa", 1, removed=(("compass", "Emil"),))
    member.receive(encode(same))
    assert member.known == same
    network.sent.clear()
    member.receive(encode(State(1, "Mallory", "1.bb", 0, added=(("open", "Door9"),))))
    assert member.known == same
    assert [m["type"] for _, m in network.sent] == ["rival"]


def test_a_robot_knows_its_coordinator_before_it_hears_from_it() -> None:
    """Emil expects Pippi, who owns the goal, to coordinate: her token going
    before any message of hers reached him makes him take over all the same
    (before, the coordinator he followed was the sender of its first message,
    and nobody took over from one that died first)."""
    emil, _, _, _ = _member()
    network, order = Network(), Succession((("Pippi", "Emil"),), after=0.0)
    member = Member(emil, network, Monitor(), succession=order, leader="Pippi")
    assert member.epoch == "" and not member.takeover_due()
    network.presence("Pippi", True)
    network.presence("Pippi", False)
    assert member.takeover_due()


def test_a_message_read_after_its_coordinator_went_does_not_bring_it_back() -> None:
    """Pippi's first commit to Emil waited in his queue while her token went
    (her process was killed just after she sent it): read after her loss, it
    makes Emil follow her run, but she stays lost, and he takes over (before,
    following a run cleared the loss, and nobody took over)."""
    _, member, network, own = _member()
    member.succession = Succession((("Pippi", "Emil"),), after=0.0)
    member.leader = "Pippi"
    network.alive = {"Pippi"}  # type: ignore[attr-defined]
    network.presence("Pippi", True)
    network.alive = set()  # type: ignore[attr-defined]
    network.presence("Pippi", False)
    member.receive(_message("commit", 1, own, epoch="1.aa"))
    assert (member.epoch, member.leader) == ("1.aa", "Pippi")
    assert member.takeover_due()
    member.receive(_message("commit", 1, None, epoch="1.aa"))  # a repeated one: still lost
    assert member.takeover_due()


def test_who_may_take_over_is_who_says_it_plans() -> None:
    """A robot run from emitted code has no planner: the robots that do pass
    it over in the order."""
    network = Network()
    network.alive = {"Pippi", "Emil", "Rasmus"}  # type: ignore[attr-defined]
    assert candidates(network, "Emil") == {"Pippi", "Emil", "Rasmus"}  # not said: every robot
    network.planners = lambda: {"Rasmus", "Mallory"}  # type: ignore[attr-defined]
    assert candidates(network, "Emil") == {"Emil", "Rasmus"}  # Mallory is not alive
    order = Succession((("Pippi", "Emil", "Rasmus"),))
    assert order.successor(0, candidates(network, "Rasmus") - {"Pippi"}, "Pippi") == "Rasmus"


def test_the_coordinator_tells_what_it_committed_once_nothing_is_in_flight() -> None:
    """Emil coordinates 6.2.2 step 2 with Pippi ready: at rest he tells her
    once; his compass fails and the switch to the cameras waits for her
    answer — nothing is told while it is in flight; once committed, she is
    told the compass out of service. Ready anew (started again), she is told
    again."""
    adaptive, network, clock, _ = _society()
    _wait(adaptive, clock, 0.1)
    _wait(adaptive, clock, 0.1)
    assert network.to("Pippi", "state") == [
        {"op": "state", "id": 0, "from": "Emil", "epoch": adaptive.deployer.epoch}
    ]
    adaptive.take(Detection("failure", "Emil", 1.0, instance=("compass", "Emil"), how="injected"))
    (prepare,) = network.to("Pippi", "prepare")
    _wait(adaptive, clock, 0.1)
    assert len(network.to("Pippi", "state")) == 1
    for phase in ("ready", "installed"):
        ack = {"type": "ack", "robot": "Pippi", "id": prepare["id"], "phase": phase}
        adaptive.receive(json.dumps({**ack, "epoch": adaptive.deployer.epoch}).encode(), "Pippi")
    _wait(adaptive, clock, 0.1)
    told = network.to("Pippi", "state")[-1]
    assert (told["id"], told["failed"]) == (prepare["id"], [["compass", "Emil"]])
    assert len(network.to("Pippi", "state")) == 2
    adaptive.receive(b'{"type": "ready", "robot": "Pippi"}', "Pippi")
    _wait(adaptive, clock, SWITCH_TIMEOUT)
    assert network.to("Pippi", "state")[-1] == told and len(network.to("Pippi", "state")) == 3
