"""The story of a trace: configurations rebuilt from switch events and from
calls, numbered like the diagrams, failures and recoveries on the row of the
robot whose resource it is."""

from __future__ import annotations

from typing import Any

import pytest

from cfgplan.report.story import configuration_of, from_records, owner

T0 = 1_795_724_275.0
"""A run's clock: seconds since the epoch."""


def _switch(t: float, cause: str, was: int | None, to: int, **parts: Any) -> dict[str, Any]:
    empty = {"functionalities": [], "channels": []}
    return {
        "event": "switch",
        "robot": "Pippi",
        "t": T0 + t,
        "cycle": 1,
        "id": 1,
        "cause": cause,
        "from_cost": was,
        "to_cost": to,
        "source": "fallback",
        "kept": parts.get("kept", empty),
        "stopped": parts.get("stopped", empty),
        "started": parts.get("started", empty),
    }


A = {
    "functionalities": ["F3: cross-door(Pippi, Door1)", "F8: camera(Emil)"],
    "channels": ["F8->F3 image(Emil)"],
}
B = {"functionalities": ["F10: compass(Pippi)"], "channels": ["F10->F3 orient(Pippi)"]}
C = {"functionalities": ["F17: camera(Pippi)"], "channels": ["F17->F3 image(Pippi)"]}


def test_configurations_come_from_the_switches_and_keep_their_numbers() -> None:
    """Before the first switch: kept + stopped; after: kept + started. Going back
    to the first configuration (other labels, same parts) is #1 again."""
    records = [
        {
            "event": "start",
            "robot": "Pippi",
            "t": T0,
            "cycle": 0,
            "transport": "x",
            "partners": ["Emil"],
            "rate": 10.0,
        },
        _switch(4.0, "compass(Pippi) failed", 44, 47, kept=A, stopped=B, started=C),
        _switch(
            9.0,
            "compass(Pippi) recovered",
            47,
            44,
            kept=A,
            stopped=C,
            started={
                "functionalities": ["F20: compass(Pippi)"],
                "channels": ["F20->F3 orient(Pippi)"],
            },
        ),
        {"event": "stop", "robot": "Pippi", "t": T0 + 12.0, "cycle": 9, "reason": "cycles"},
    ]
    story = from_records(records)
    assert story.clock == "seconds since the run started"
    assert [(s.number, s.config.cost, s.start, s.end) for s in story.spans] == [
        (1, 44, 0.0, 4.0),
        (2, 47, 4.0, 9.0),
        (1, 44, 9.0, 12.0),
    ]
    first = story.spans[0].config
    assert [str(f) for f in first.functionalities] == [
        "F3: cross-door(Pippi, Door1)",
        "F8: camera(Emil)",
        "F10: compass(Pippi)",
    ]
    assert {(c.source, c.target, c.kind) for c in first.channels} == {
        ("F8", "F3", "global"),
        ("F10", "F3", "local"),
    }
    assert [m.text for m in story.of("switch")] == [
        "44 → 47: compass(Pippi) failed",
        "47 → 44: compass(Pippi) recovered",
    ]
    assert story.steps[0].goal == "cross-door(Pippi, Door1)"


def test_a_run_that_never_switched_is_read_from_its_calls() -> None:
    """Functionalities from the calls, a local channel from one call's output to
    another's input on the same robot, a global one from a send."""

    def call(
        t: float,
        robot: str,
        label: str,
        name: str,
        args: list[str],
        inputs: list[list[str]],
        outputs: list[list[str]],
    ) -> dict[str, Any]:
        return {
            "event": "call",
            "robot": robot,
            "t": T0 + t,
            "cycle": 1,
            "label": label,
            "functionality": name,
            "args": args,
            "status": "ran",
            "inputs": [{"data": d, "value": 1} for d in inputs],
            "outputs": [{"data": d, "value": 1} for d in outputs],
        }

    records = [
        call(0.1, "Emil", "F8", "camera", ["Emil"], [], [["image", "Emil"]]),
        call(
            0.1,
            "Emil",
            "F9",
            "measure-door",
            ["Emil", "Door1"],
            [["image", "Emil"]],
            [["pos", "Emil", "Door1"]],
        ),
        {
            "event": "send",
            "robot": "Emil",
            "t": T0 + 0.2,
            "cycle": 1,
            "channel": "F9->F3 (pos Emil Door1)",
            "data": ["pos", "Emil", "Door1"],
            "seq": 1,
            "to": "Pippi",
            "value": 1,
        },
        call(0.3, "Pippi", "F3", "cross-door", ["Pippi", "Door1"], [["pos", "Emil", "Door1"]], []),
    ]
    story = from_records(records)
    (span,) = story.spans
    assert {(c.source, c.target, c.kind, c.data) for c in span.config.channels} == {
        ("F8", "F9", "local", ("image", "Emil")),
        ("F9", "F3", "global", ("pos", "Emil", "Door1")),
    }
    assert story.robots == ["Emil", "Pippi"]
    assert story.end == pytest.approx(0.2)


def test_failure_and_recovery_go_on_the_row_of_the_resources_robot() -> None:
    """Pippi (the coordinator) writes both, Emil detects one, Pippi the other:
    both on Emil's row, for compass(Emil) is Emil's; a lost robot on its own row."""
    base = {"robot": "Pippi", "cycle": 1, "kind": "functionality"}
    records = [
        {
            **base,
            "event": "failure",
            "t": 1.0,
            "detected_by": "Emil",
            "resource": "compass(Emil)",
            "how": "reported",
            "detail": "",
            "withdrawn": [],
        },
        {
            **base,
            "event": "recovery",
            "t": 5.0,
            "detected_by": "Pippi",
            "resource": "compass(Emil)",
            "how": "probe",
        },
        {
            **base,
            "event": "failure",
            "t": 6.0,
            "detected_by": "Pippi",
            "resource": "Emil",
            "how": "lost",
            "detail": "",
            "withdrawn": [],
            "kind": "robot",
        },
    ]
    story = from_records(records, origin=0.0)
    assert story.clock == "simulated time (s)"
    assert [(m.what, m.robot, m.t) for m in story.marks] == [
        ("failure", "Emil", 1.0),
        ("recovery", "Emil", 5.0),
        ("failure", "Emil", 6.0),
    ]
    assert owner("transform-info(Emil, Pippi, Door1)", ["Pippi", "Emil"]) == "Emil"
    assert owner("(door Door2)", ["Pippi"], "Pippi") == "Pippi"


def test_printed_parts_that_do_not_read_make_no_configuration() -> None:
    assert configuration_of(["nonsense", "F1: noargs()"], ["F1->F2 x(y)"]) is None
