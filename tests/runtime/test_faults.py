"""The ``--inject`` syntax: scripted faults for tests and demos (5.5)."""

from __future__ import annotations

import pytest

from cfgplan.runtime.errors import RunError
from cfgplan.runtime.faults import Injection, misaimed, parse_injection, term_text


@pytest.mark.parametrize(
    ("text", "action", "target", "cycle", "seconds"),
    [
        ("fail compass(Emil) at cycle 20", "fail", ("compass", "Emil"), 20, None),
        ("fail (compass Emil) at 2.5s", "fail", ("compass", "Emil"), None, 2.5),
        ("recover compass(Emil) at 3 s", "recover", ("compass", "Emil"), None, 3.0),
        (
            "fail transform-info(Pippi, Emil, Door1) at cycle 2",
            "fail",
            ("transform-info", "Pippi", "Emil", "Door1"),
            2,
            None,
        ),
        ("kill Emil at cycle 40", "kill", ("Emil",), 40, None),
        ("recover Emil at 0s", "recover", ("Emil",), None, 0.0),
        ("retract (compass Emil) at cycle 3", "retract", ("compass", "Emil"), 3, None),
        ("  assert   in(Pippi, Room2)  at  cycle 7 ", "assert", ("in", "Pippi", "Room2"), 7, None),
    ],
)
def test_every_form_of_the_syntax(
    text: str, action: str, target: tuple[str, ...], cycle: int | None, seconds: float | None
) -> None:
    found = parse_injection(text)
    assert (found.action, found.target, found.cycle, found.seconds) == (
        action,
        target,
        cycle,
        seconds,
    )
    assert found.text == " ".join(text.split())


@pytest.mark.parametrize(
    ("text", "says"),
    [
        ("fail compass(Emil)", "not a fault I can inject"),
        ("break compass(Emil) at cycle 2", "not a fault I can inject"),
        ("fail Emil at cycle 2", "fail takes a functionality instance"),
        ("kill compass(Emil) at cycle 2", "kill takes a robot's name"),
        ("retract Emil at cycle 2", "retract takes a fact"),
        ("fail compass(Emil) at cycle 0", "a whole number from 1, not '0'"),
        ("fail compass(Emil) at cycle two", "a whole number from 1, not 'two'"),
        ("fail compass(Emil) at -1s", "seconds such as 2.5s, not '-1's"),
        ("fail compass(Emil at cycle 2", "neither NAME(ARGS)"),
    ],
)
def test_bad_injections_say_what_is_expected(text: str, says: str) -> None:
    with pytest.raises(RunError) as caught:
        parse_injection(text)
    assert says in caught.value.message and repr(text) in caught.value.message


def test_where_and_when_an_injection_applies() -> None:
    fail = parse_injection("fail compass(Emil) at cycle 20")
    assert fail.robot == "Emil" and not fail.on_robot and not fail.on_facts
    assert not fail.due(19, 100.0) and fail.due(20, 0.0)
    timed = parse_injection("kill Pippi at 2.5s")
    assert timed.robot == "Pippi" and timed.on_robot
    assert not timed.due(1000, 2.4) and timed.due(1, 2.5)
    fact = parse_injection("retract (compass Emil) at cycle 1")
    assert fact.robot is None and fact.on_facts
    assert term_text(fail.target) == "compass(Emil)" and term_text(timed.target) == "Pippi"
    assert isinstance(fact, Injection)


AGENTS = ("Pippi", "Emil")
ARITIES = [("compass", 1), ("camera", 1), ("measure-door", 2)]


@pytest.mark.parametrize(
    ("text", "message", "hint"),
    [
        ("kill Emli at cycle 3", "no robot Emli in this society", "did you mean Emil?"),
        (
            "recover emil at 2s",
            "no robot emil in this society",
            "symbols are case-sensitive: did you mean Emil?",
        ),
        ("fail compass(Nobody) at cycle 3", "no robot Nobody", "its robots: Pippi, Emil"),
        ("fail compas(Emil) at cycle 3", "no functionality compas", "did you mean compass?"),
        (
            "recover gizmo(Emil) at cycle 3",
            "no functionality gizmo in the domain",
            "its functionalities: compass, camera, measure-door",
        ),
        ("fail compass(Emil, x) at cycle 3", "compass takes 1 argument(s), not 2", "compass(Emil)"),
    ],
)
def test_a_fault_aimed_at_nothing_is_named(text: str, message: str, hint: str) -> None:
    """A typo in --inject made the fault a silent no-op (a newcomer's ``kill
    Emli``: no console line, no trace event, exit 0); now it says what is wrong."""
    wrong = misaimed(parse_injection(text), AGENTS, ARITIES)
    assert wrong is not None
    assert wrong.message == f"--inject {text!r}: {message}" or wrong.message.startswith(
        f"--inject {text!r}: {message}"
    )
    assert wrong.hint is not None and hint in wrong.hint


@pytest.mark.parametrize(
    "text",
    [
        "kill Emil at cycle 3",
        "recover Pippi at 2s",
        "fail measure-door(Emil, Door1) at cycle 3",
        "retract (compass Anyone) at cycle 2",  # a state update may name any fact
        "assert (door Door9) at cycle 2",
    ],
)
def test_a_fault_aimed_at_the_society_passes(text: str) -> None:
    assert misaimed(parse_injection(text), AGENTS, ARITIES) is None


def test_without_the_domain_only_the_robot_is_checked() -> None:
    """An emitted program knows its robots, not the domain."""
    assert misaimed(parse_injection("fail gizmo(Emil) at cycle 3"), AGENTS) is None
    assert misaimed(parse_injection("fail gizmo(Emli) at cycle 3"), AGENTS) is not None
