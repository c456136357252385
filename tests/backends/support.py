"""Shared by the backend and runtime tests: planned configurations, golden files,
and the thesis's own text of 4.6 / 5.4 to compare with."""

from __future__ import annotations

import functools
import os
import re
from pathlib import Path

from cfgplan.backends.divide import Individual
from cfgplan.backends.wiring import RobotPart, wire
from cfgplan.configuration.model import Channel, Configuration, FunctionalityInstance
from cfgplan.ir.model import Atom, Domain, Functionality
from cfgplan.notation import call_text
from cfgplan.planner import plan
from cfgplan.problem import Problem, load

ROOT = Path(__file__).resolve().parents[2]
DOMAINS = ROOT / "domains"
GOLDEN = ROOT / "tests" / "golden"
EXAMPLE_IMPL = ROOT / "examples" / "cross-door" / "impl.py"

UPDATE = os.environ.get("CFGPLAN_UPDATE_GOLDEN", "") not in ("", "0")
"""CFGPLAN_UPDATE_GOLDEN=1 pytest ... rewrites the golden files (check them by eye)."""

MEDIA_STATE = "state-4.6-media.lisp"
BANDWIDTH_DOMAIN = "domain-bandwidth.lisp"


def bundled_pairs() -> list[tuple[Path, Path]]:
    """Every domain with every state of its folder that has a goal; the
    bandwidth domain goes with the media state, domain.lisp with the others."""
    pairs: list[tuple[Path, Path]] = []
    for domain in sorted(DOMAINS.glob("*/domain*.lisp")):
        for state in sorted(domain.parent.glob("state-*.lisp")):
            if (domain.name == BANDWIDTH_DOMAIN) != (state.name == MEDIA_STATE):
                continue
            if "(goal" not in state.read_text(encoding="utf-8"):
                continue
            pairs.append((domain, state))
    return pairs


CROSS = ("cross-door/domain.lisp", "cross-door/state-6.2.2-step1.lisp")
CARRY = ("carry-bar/domain.lisp", "carry-bar/state-6.3.2.lisp")


@functools.cache
def planned(domain: str, state: str, rank: int = 1) -> tuple[Problem, Configuration]:
    """The problem and its configuration of ``rank``."""
    problem = load(DOMAINS / domain, DOMAINS / state)
    configs, _ = plan(problem.task, problem.goal_call, limit=rank)
    assert len(configs) >= rank
    return problem, configs[rank - 1]


def cross_door_44() -> tuple[Problem, Configuration]:
    problem, config = planned(*CROSS)
    assert config.cost == 44, "the planner no longer finds the configuration of 4.6 first"
    return problem, config


def carry_bar_33() -> tuple[Problem, Configuration]:
    problem, config = planned(*CARRY)
    assert config.cost == 33, "the planner no longer finds the configuration of 6.3.2 first"
    return problem, config


def check_golden(name: str, text: str) -> None:
    """``text`` equals tests/golden/NAME, byte for byte (or rewrites it when UPDATE)."""
    path = GOLDEN / name
    if UPDATE:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")
        return
    assert path.exists(), f"missing golden {path}; make it with CFGPLAN_UPDATE_GOLDEN=1"
    assert text == path.read_text(encoding="utf-8"), f"output differs from golden {path}"


# Section 4.6 / 5.4: the final configuration, functionalities in the thesis's list order.
THESIS_FUNCTIONALITIES = [
    ("F109", "cross-door(Pippi, Door1)"),
    ("F113", "transform-info(Emil, Pippi, Door1)"),
    ("F129", "measure-robot-pos(Emil, Pippi)"),
    ("F118", "measure-robot-orient-compass(Emil, Pippi)"),
    ("F117", "compass(Emil)"),
    ("F116", "compass(Pippi)"),
    ("F115", "measure-door(Emil, Door1)"),
    ("F114", "camera(Emil)"),
]

# Section 5.4: "the order of functionalities is determined, and becomes".
THESIS_SORTED = ["F117", "F116", "F114", "F129", "F118", "F115", "F113", "F109"]


def thesis_labels(config: Configuration) -> dict[str, str]:
    """Thesis label -> our label, matched by functionality name and arguments."""
    ours = {call_text((f.name, *f.args)): f.label for f in config.functionalities}
    return {thesis: ours[text] for thesis, text in THESIS_FUNCTIONALITIES}


def relabel(text: str, labels: dict[str, str]) -> str:
    """Replace the thesis's labels (F109 ...) in ``text`` by ours."""
    return re.sub(r"\bF\d+\b", lambda m: labels[m.group(0)], text)


def one_robot_part(channels: list[tuple[str, str, tuple[str, ...]]]) -> RobotPart:
    """A robot part built by hand (no planner), for what no bundled domain has.

    Robot R: two producers P1, P2 of (x R) and a consumer C of (x R), (y R)."""
    domain = Domain(
        functionalities=(
            Functionality(
                name=Atom(predicate="p", args=("?r",)), outputs=(Atom(predicate="x", args=("?r",)),)
            ),
            Functionality(
                name=Atom(predicate="c", args=("?r", "?o")),
                inputs=(Atom(predicate="x", args=("?r",)), Atom(predicate="y", args=("?r",))),
            ),
        )
    )
    fs = (
        FunctionalityInstance(label="F1", name="p", args=("R",)),
        FunctionalityInstance(label="F2", name="p", args=("R",)),
        FunctionalityInstance(label="F3", name="c", args=("R", "Obj")),
    )
    chs = tuple(
        Channel(kind="local", source=s, target=t, source_robot="R", target_robot="R", data=d)
        for s, t, d in channels
    )
    ind = Individual("R", fs, chs)
    return RobotPart(ind, wire(ind, domain))
