"""The LET/LAMBDA translation of 5.3, against the code of 5.4 and golden files."""

from __future__ import annotations

import re
from dataclasses import replace

import pytest

from cfgplan.backends.lisp import call_form, to_lisp
from cfgplan.backends.wiring import Call, deploy
from cfgplan.diagnostics import CfgplanError
from tests.backends.support import (
    carry_bar_33,
    check_golden,
    cross_door_44,
    one_robot_part,
    relabel,
    thesis_labels,
)

# Section 5.4, "The finished executable configurations", as printed (typographic
# quotes made ASCII). Two typos of the thesis: Emil's CH-1 names 'F128 where the
# configuration says F114, and the prose after the code says CH-4 where the code
# uses CH-2 (the global-orient of Pippi); the code is right there.
THESIS_PIPPI = """
(LET ((CH-1 (make-global-channel 'Emil 'F116 'F118 '(global-orient Pippi)))
(CH-2 (make-global-channel 'Emil 'F113 'F109 '(pos Pippi Door1)))
(CH-3 (make-global-channel 'Emil 'F113 'F109 '(orient Pippi Door1))))
(LAMBDA NIL (PROGN (compass (LIST CH-1)) (cross-door 'Door1 CH-2 CH-3))) )
"""
THESIS_EMIL = """
(LET ((CH-1 (make-local-channel 'Emil 'F128 'F129 '(image Emil)))
(CH-2 (make-global-channel 'Pippi 'F116 'F118 '(global-orient Pippi)))
(CH-3 (make-local-channel 'Emil 'F117 'F118 '(global-orient Emil)))
(CH-4 (make-local-channel 'Emil 'F114 'F115 '(image Emil)))
(CH-5 (make-local-channel 'Emil 'F115 'F113 '(pos Emil Door1)))
(CH-6 (make-local-channel 'Emil 'F115 'F113 '(orient Emil Door1)))
(CH-7 (make-local-channel 'Emil 'F118 'F113 '(orient Emil Pippi)))
(CH-8 (make-local-channel 'Emil 'F129 'F113 '(pos Emil Pippi)))
(CH-9 (make-global-channel 'Pippi 'F113 'F109 '(pos Pippi Door1)))
(CH-10 (make-global-channel 'Pippi 'F113 'F109 '(orient Pippi Door1))))
(LAMBDA NIL (PROGN (compass (LIST CH-3)) (camera (LIST CH-1 CH-4))
(measure-robot-pos 'Pippi CH-1 (LIST CH-8))
(measure-robot-orient-compass 'Pippi CH-3 CH-2 (LIST CH-7))
(measure-door 'Door1 CH-4 (LIST CH-5) (LIST CH-6))
(transform-info 'Pippi 'Door1 CH-7 CH-8 CH-6 CH-5 (LIST CH-10) (LIST CH-9)))) )
"""


def _tokens(code: str) -> str:
    """The code without comments and layout: equal tokens, equal code."""
    code = re.sub(r";[^\n]*", "", code)
    code = re.sub(r"\s+", " ", code)
    return re.sub(r"\(\s+", "(", re.sub(r"\s+\)", ")", code)).strip()


def test_cross_door_44_is_the_code_of_5_4() -> None:
    problem, config = cross_door_44()
    labels = thesis_labels(config)
    labels["F128"] = labels["F114"]  # the thesis's typo: F128 is F114, camera(Emil)
    pippi, emil = deploy(config, problem.domain)
    assert _tokens(to_lisp(pippi)) == _tokens(relabel(THESIS_PIPPI, labels))
    assert _tokens(to_lisp(emil)) == _tokens(relabel(THESIS_EMIL, labels))


@pytest.mark.parametrize("robot", ["Pippi", "Emil"])
def test_cross_door_44_golden(robot: str) -> None:
    """5.4 laid out as 5.4 prints it, one channel a line."""
    problem, config = cross_door_44()
    (part,) = [p for p in deploy(config, problem.domain) if p.robot == robot]
    check_golden(f"cross-door-44/{robot.lower()}.lisp", to_lisp(part))


@pytest.mark.parametrize("robot", ["Pippi", "Emil"])
def test_carry_bar_33_golden(robot: str) -> None:
    """6.3.2, the cost-33 configuration: Emil's laser output dist goes to three
    channels, one of them global to Pippi's lead-robot."""
    problem, config = carry_bar_33()
    (part,) = [p for p in deploy(config, problem.domain) if p.robot == robot]
    text = to_lisp(part)
    check_golden(f"carry-bar-33/{robot.lower()}.lisp", text)
    if robot == "Emil":
        assert re.search(
            r"\(meas-robot-angle-dist-laser 'Pippi CH-1 \(LIST CH-\d+\) "
            r"\(LIST CH-\d+ CH-\d+ CH-\d+\)\)",
            text,
        )


def test_several_channels_into_one_input_and_an_input_without_one() -> None:
    """Silent in the thesis: (LIST CH-a CH-b) for several channels, NIL for none."""
    part = one_robot_part([("F1", "F3", ("x", "R")), ("F2", "F3", ("x", "R"))])
    text = to_lisp(part)
    assert "(c 'Obj (LIST CH-1 CH-2) NIL)" in text
    assert "(p (LIST CH-1))" in text and "(p (LIST CH-2))" in text


def test_a_channel_the_functionality_has_no_input_for_is_an_error() -> None:
    with pytest.raises(CfgplanError, match=r"carries x\(R\), but F2: p\(R\) has no such input"):
        one_robot_part([("F1", "F2", ("x", "R"))])
    with pytest.raises(CfgplanError, match=r"carries z\(R\), but F1: p\(R\) has no such output"):
        one_robot_part([("F1", "F3", ("z", "R"))])


def test_a_functionality_named_as_the_forms_own_operator_is_an_error() -> None:
    """``(LIST (LIST CH-1))`` would make a list, not call LIST: no form of 5.3
    calls it, so emitting says so (Python still can)."""
    (producer, *_rest) = one_robot_part([("F1", "F3", ("x", "R"))]).calls

    def named(name: str) -> Call:
        renamed = producer.functionality.model_copy(update={"name": name})
        return replace(producer, functionality=renamed)

    with pytest.raises(CfgplanError, match="the functionality LIST cannot be called"):
        call_form(named("LIST"))
    assert call_form(named("list")).startswith("(|list| ")
