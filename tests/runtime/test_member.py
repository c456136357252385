"""A robot's side of the switch protocol (5.5, cfgplan.runtime.member): what
it sends the coordinator."""

from __future__ import annotations

import json
import time
from dataclasses import replace
from typing import Any

import pytest

from cfgplan.backends.part import runtime_part
from cfgplan.backends.wiring import deploy
from cfgplan.runtime import Adaptation, Registry, society
from cfgplan.runtime.events import Call
from cfgplan.runtime.executor import Robot
from cfgplan.runtime.member import Member
from cfgplan.runtime.monitor import Detection, Monitor
from cfgplan.runtime.part import part_to_json
from tests.backends.support import EXAMPLE_IMPL, cross_door_44


class Network:
    """Keeps what is published; nothing is delivered."""

    society = "test"

    def __init__(self) -> None:
        self.sent: list[tuple[str, dict[str, Any]]] = []
        self.presence_listeners: list[Any] = []

    def presence(self, robot: str, alive: bool) -> None:
        """``robot``'s token appears or goes, as the Zenoh transport tells it."""
        for listener in self.presence_listeners:
            listener(robot, alive)

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


def _member() -> tuple[Robot, Member, Network, dict[str, Any]]:
    """Emil of cross-door 44 following a coordinator, and his part as sent."""
    problem, config = cross_door_44()
    parts = [runtime_part(p) for p in deploy(config, problem.domain)]
    running = society(parts, Registry.load(EXAMPLE_IMPL))
    emil = next(r for r in running.robots if r.name == "Emil")
    network = Network()
    own = part_to_json(next(p for p in parts if p.robot == "Emil"))
    member = Member(emil, network, Monitor())
    ready = {"type": "ready", "robot": "Emil", "instance": member.instance}
    assert network.sent == [("cfgplan/test/coordinator/Emil", ready)]
    network.sent.clear()
    return emil, member, network, own


def _message(op: str, number: object, part: object = None, epoch: str = "A") -> bytes:
    message: dict[str, object] = {"op": op, "id": number, "from": "Pippi", "epoch": epoch}
    if part is not None:
        message["part"] = part
    # an infinite float as a writer other than Python's would put it (JSON has no Infinity)
    return json.dumps(message).replace("Infinity", "1e999").encode()


def _acks(network: Network) -> list[tuple[int, str]]:
    return [(m["id"], m["phase"]) for _, m in network.sent if m["type"] == "ack"]


@pytest.mark.parametrize("number", ["1e999", "Infinity", "1.5", "true", '"1"', "null"])
def test_a_message_whose_id_is_no_whole_number_is_an_error_not_a_crash(number: str) -> None:
    """A message from another process is read, never trusted: ``1e999`` made
    ``int()`` raise OverflowError out of the robot's loop."""
    emil, member, network, _ = _member()
    member.receive(b'{"op":"abort","id":' + number.encode() + b"}")
    member.receive(b'{"op":"prepare","id":' + number.encode() + b"}")
    assert network.sent == []
    errors = [e for e in emil.events if getattr(e, "what", "") == "error"]
    # not JSON at all (Infinity), the two are one kind: one said a second, the other counted
    assert len(errors) == (1 if number == "Infinity" else 2)
    assert "cannot be read" in dict(errors[0].info)["message"]


@pytest.mark.parametrize(
    ("where", "value", "why"),
    [
        ("freq", float("inf"), "not a frequency a functionality can run at"),
        ("freq", 0, "not a frequency a functionality can run at"),
        ("other", ["Pippi"], "is not a name"),
        ("index", 1.0, "is not a channel index"),
        ("objects", "Door1", "is not a list of names"),
    ],
)
def test_a_part_that_could_fail_once_running_is_refused_at_prepare(
    where: str, value: object, why: str
) -> None:
    """What passes a prepare installs and runs: an infinite frequency (a
    period of 0, ZeroDivisionError in the loop) or an unhashable robot name
    (TypeError at commit) was answered ``ready``."""
    _, member, network, own = _member()
    call = own["calls"][0]
    if where == "freq":
        call[5] = value
    elif where == "objects":
        call[2] = value
    elif where == "index":
        call[3] = [[value]]
    else:
        own["channels"].append(["global", "F1", "F2", ["x"], value])
    member.receive(_message("prepare", 1, own))
    ((number, phase),) = _acks(network)
    assert (number, phase) == (1, "refused") and why in network.sent[-1][1]["reason"]
    member.receive(_message("commit", 1))
    assert member.current == 0 and _acks(network)[-1] == (1, "refused")


def test_a_part_whose_implementation_cannot_take_its_arguments_is_refused_at_prepare() -> None:
    """Prepare checks what install checks: an implementation of the wrong
    arity answered ``ready`` and then ended the robot's process at commit."""
    base = Registry.load(EXAMPLE_IMPL)

    def no_arguments() -> None:
        return None

    broken = Registry(
        replace(base.lookup(n), function=no_arguments) if n == "measure-door" else base.lookup(n)
        for n in base.names()
    )
    emil, member, network, own = _member()
    emil.registry = broken  # as if its implementations were changed since it started
    member.receive(_message("prepare", 1, own))
    reason = network.sent[-1][1]["reason"]
    assert _acks(network) == [(1, "refused")] and "measure-door(Emil, Door1) calls it" in reason


def test_a_coordinator_started_again_is_followed_from_its_first_id() -> None:
    """A coordinator that starts again numbers its configurations from 0: its
    messages carry another epoch, and the robot follows them once the one it
    followed went away (before, a commit of id 0 after id 1 was dropped
    without an answer for good)."""
    _, member, network, own = _member()
    member.receive(_message("prepare", 1, own, epoch="A"))
    member.receive(_message("commit", 1, epoch="A"))
    assert member.current == 1 and _acks(network) == [(1, "ready"), (1, "installed")]
    member.receive(_message("prepare", 1, own, epoch="A"))  # an old switch: ignored
    assert len(_acks(network)) == 2
    network.presence("Pippi", False)  # the coordinator's process died ...
    network.presence("Pippi", True)  # ... and it was started again
    member.receive(_message("commit", 0, own, epoch="B"))  # the new one re-synchronises
    assert member.current == 0 and _acks(network)[-1] == (0, "installed")
    assert network.sent[-1][1]["epoch"] == "B"
    member.receive(_message("prepare", 1, own, epoch="B"))
    assert 1 in member.pending
    member.receive(_message("finish", 1, epoch="B"))
    assert member.finished == "achieved"


def test_a_second_coordinator_is_told_it_is_a_rival_and_not_followed() -> None:
    """While the coordinator it follows is alive, a
    robot ignores another coordinator's messages — a commit, a finish, a
    hello — and tells it once that it is a rival (it then stops); the
    console says so once. Once its coordinator is gone, a new one is followed."""
    emil, member, network, own = _member()
    member.receive(_message("commit", 1, own, epoch="A"))
    network.sent.clear()
    for op, number in (("commit", 0), ("finish", 1), ("hello", 0)):
        member.receive(_message(op, number, own if op == "commit" else None, epoch="B"))
    assert member.current == 1 and member.epoch == "A" and member.finished is None
    rival = {"type": "rival", "robot": "Emil", "epoch": "B", "leader": "Pippi", "over": "A"}
    assert [m for _, m in network.sent] == [rival]
    said = [dict(e.info)["message"] for e in emil.events if getattr(e, "what", "") == "error"]
    assert said == ["a second coordinator (Pippi) of society test is ignored: Pippi coordinates it"]
    network.presence("Pippi", False)
    member.receive(_message("commit", 0, own, epoch="B"))
    assert (member.epoch, member.current) == ("B", 0)


def test_a_second_process_of_a_robot_stops_when_told_it_is_a_duplicate() -> None:
    """The coordinator names the process to stop by the instance in its ready:
    the other process of the same robot name ignores it."""
    _, member, _, _ = _member()
    told = {"op": "duplicate", "from": "Pippi", "epoch": "A", "instance": "not-mine"}
    member.receive(json.dumps(told).encode())
    assert member.refused is None
    member.receive(json.dumps({**told, "instance": member.instance}).encode())
    assert member.refused == (
        "another process runs robot Emil in society test (the coordinator, Pippi, keeps it): "
        "this one stops"
    )


def test_told_to_finish_a_robot_says_so_answers_and_takes_no_one_for_lost() -> None:
    """A robot told the task is accomplished records ``finish`` (the
    console's "the task is accomplished" line), answers ``finished`` so that
    the coordinator may leave, and the coordinator leaving is no loss."""
    emil, member, network, _ = _member()
    finish = {"op": "finish", "id": 2, "from": "Pippi", "epoch": "A", "goal": "g(Emil)"}
    member.receive(json.dumps(finish).encode())
    member.receive(json.dumps(finish).encode())  # said again: answered again, noted once
    assert member.finished == "achieved"
    assert _acks(network) == [(2, "finished"), (2, "finished")]
    assert {m["epoch"] for _, m in network.sent} == {"A"}
    noted = [e for e in emil.events if isinstance(e, Adaptation) and e.what == "finish"]
    assert [dict(e.info) for e in noted] == [{"id": 2, "from": "Pippi", "goal": "g(Emil)"}]
    emil._presence("Pippi", False)  # the coordinator leaves, as the transport reports it
    assert not [e for e in emil.events if e.kind == "robot-lost"]


def test_a_robot_says_it_is_ready_when_it_can_receive_and_when_greeted() -> None:
    """The coordinator sends a robot nothing of a switch before it
    says it is ready (its subscriber exists); a coordinator that sees its
    token without that word (started after it) greets it, and it answers."""
    emil, member, network, _ = _member()  # _member checks the first word: ready
    member.receive(json.dumps({"op": "hello", "from": "Pippi", "epoch": "B"}).encode())
    member.receive(json.dumps({"op": "hello", "from": "Pippi", "epoch": "C"}).encode())
    ready = {"type": "ready", "robot": "Emil", "instance": member.instance}
    assert [m for _, m in network.sent] == [ready] * 2
    assert member.epoch == "" and member.current == 0  # a greeting changes nothing
    coordinator = Member(emil, Network(), forward=False)  # the coordinator's own member
    assert coordinator.network.sent == []  # type: ignore[attr-defined]


def test_a_call_that_fails_is_told_to_the_coordinator_once_a_run_with_its_message() -> None:
    """A helper's implementation raised and the coordinator's console
    said only that its input went stale; now it gets the helper's own message
    (its file and line), once for each run of failed calls, clipped."""
    emil, member, network, _ = _member()
    failing = Call(
        robot="Emil",
        t=1.0,
        label="F7",
        name="transform-info",
        args=("Emil", "Pippi", "Door1"),
        status="error",
        error="the implementation raised ZeroDivisionError: division by zero (impl.py:12 in f)"
        + "!" * 10_000,
    )
    for status in ("error", "error", "timeout", "ran", "error"):
        emil.record(replace(failing, status=status))  # type: ignore[arg-type]
        member.report()
    emil.record(replace(failing, label="F8", failure="reported"))  # a resource: a detection
    member.report()
    told = [m for _, m in network.sent if m["type"] == "call-error"]
    assert len(told) == 2 and told[0] == told[1]
    assert told[0]["functionality"] == "F7: transform-info(Emil, Pippi, Door1)"
    assert told[0]["error"].startswith("the implementation raised ZeroDivisionError")
    assert len(told[0]["error"]) == 4000


@pytest.mark.parametrize("without", ["stop", "run"])
def test_a_robot_whose_coordinator_is_gone_past_the_hold_stops_its_part(without: str) -> None:
    """Measured: after ``kill -9`` of the coordinator, a helper's action ran
    on at 20 Hz for 15 s with nobody watching. Its coordinator gone for the
    hold, a robot stops its part by default (every functionality stopped,
    an ``install`` of nothing recorded, the console told) and says it is
    ready again when the coordinator's token comes back, so that it is sent
    its part; ``--without-coordinator run`` runs on, said too."""
    emil, member, network, own = _member()
    member.without, member.hold = without, 0.05
    member.receive(_message("commit", 1, own))
    assert member.leader == "Pippi" and emil.wrappers
    network.sent.clear()
    network.presence("Pippi", False)
    member.report()
    assert not member.orphaned and emil.wrappers  # within the hold
    time.sleep(0.1)
    member.report()
    errors = [dict(e.info)["message"] for e in emil.events if getattr(e, "what", "") == "error"]
    assert len(errors) == 1 and f"--without-coordinator {without}" in errors[0]
    installs = [e for e in emil.events if getattr(e, "what", "") == "install"]
    if without == "run":
        assert not member.orphaned and emil.wrappers and len(installs) == 1
        return
    assert member.orphaned and not emil.wrappers and len(installs) == 2
    member.report()  # said once
    assert len([e for e in emil.events if getattr(e, "what", "") == "error"]) == 1
    network.presence("Pippi", True)
    assert [m["type"] for _, m in network.sent] == ["ready"]
    member.receive(_message("commit", 1, own))  # the coordinator sends its part again
    assert not member.orphaned and emil.wrappers
