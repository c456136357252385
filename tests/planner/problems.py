"""Problems given as text (generated or written in a test), read as
:func:`cfgplan.problem.load` reads files, and planned: what the planner's
tests share (the examples themselves: :mod:`tests.planner.generated`)."""

from __future__ import annotations

import tempfile
from dataclasses import dataclass
from functools import cache
from pathlib import Path

from hypothesis import HealthCheck, settings

from cfgplan.check import check
from cfgplan.configuration.cost import Weights
from cfgplan.configuration.model import Configuration
from cfgplan.diagnostics import CfgplanError
from cfgplan.ir.model import Domain
from cfgplan.planner import plan
from cfgplan.planner.options import SearchOptions
from cfgplan.planner.task import compile_task
from cfgplan.problem import Problem, load
from cfgplan.syntax.reader import SourceFile, parse, state_from


@dataclass(frozen=True)
class Generated:
    """A domain and a state as source text, with the weights to plan with."""

    domain: str
    state: str
    weights: Weights

    def __str__(self) -> str:
        return (
            f";; weights: {self.weights}\n;; domain.lisp\n{self.domain}\n"
            f";; state.lisp\n{self.state}"
        )


def load_generated(example: Generated) -> Problem:
    """Write the example to files and read them with :func:`cfgplan.problem.load`."""
    with tempfile.TemporaryDirectory() as tmp:
        domain, state = Path(tmp) / "domain.lisp", Path(tmp) / "state.lisp"
        domain.write_text(example.domain, encoding="utf-8")
        state.write_text(example.state, encoding="utf-8")
        return load(domain, state, None, example.weights)


@cache
def _form(text: str) -> SourceFile:
    return parse(text, "domain.lisp")


def solve(example: Generated) -> Problem:
    """What :func:`load_generated` returns, faster: the generated domains share
    most of their forms, so each form is parsed once (parsing dominates the
    run time of these tests). Then checked and compiled as load() does."""
    forms = [_form("(make-" + f) for f in ("\n" + example.domain).split("\n(make-")[1:]]
    domain = Domain(
        functionalities=tuple(f for form in forms for f in form.functionalities),
        methods=tuple(m for form in forms for m in form.methods),
    )
    state = state_from(parse(example.state, "state.lisp"))
    assert state.goal is not None
    diagnostics = check(domain, state, state.goal)
    if any(d.is_error for d in diagnostics):
        raise CfgplanError(diagnostics)
    task = compile_task(domain, state, example.weights)
    return Problem(domain, state, state.goal, task)


FIRST_NODE = SearchOptions(warm=0, trial=10**9)
"""The partitioned bound (and its media test) tried from the first node and
never given up: left to itself, a search this small never computes it
(:attr:`cfgplan.planner.options.SearchOptions.warm`)."""


def run(
    problem: Problem,
    *,
    limit: int | None = None,
    distinct: bool,
    options: SearchOptions | None = None,
) -> list[Configuration]:
    configs, _ = plan(
        problem.task, problem.goal_call, limit=limit, distinct=distinct, options=options
    )
    return configs


PROPERTY = settings(
    derandomize=True,
    max_examples=100,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)


def load_text(domain: str, state: str, weights: Weights | None = None) -> Problem:
    return load_generated(Generated(domain, state, weights or Weights()))
