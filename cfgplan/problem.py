"""A planning problem: domain, state and goal read, checked and compiled.

This is the front of the pipeline every command shares (read -> check ->
compile); the planner and the backends take it from here.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from cfgplan.check import check
from cfgplan.configuration.cost import Weights
from cfgplan.diagnostics import CfgplanError, Diagnostic, error
from cfgplan.ir.model import Domain, Goal, Span, State
from cfgplan.planner.task import Ground, Task, compile_task, pattern
from cfgplan.syntax.reader import parse, read_domain, read_state

GOAL_SOURCE = "--goal"


@dataclass
class Problem:
    """Everything needed to plan, plus the texts to quote in messages."""

    domain: Domain
    state: State
    goal: Goal
    task: Task
    sources: dict[str, str]
    warnings: list[Diagnostic] = field(default_factory=list)

    @property
    def goal_call(self) -> Ground:
        return pattern(self.goal.call)


def parse_goal(text: str) -> Goal:
    """A goal given on the command line: ``(do-cross-door Pippi Door1)`` or
    ``do-cross-door(Pippi, Door1)``."""
    wrapped = f"(goal {text})"
    source = parse(wrapped, GOAL_SOURCE)
    if len(source.goals) != 1:
        span = Span(file=GOAL_SOURCE, line=1, column=1, end_line=1, end_column=1)
        raise error("expected one method instance such as (do-cross-door Pippi Door1)", span)
    return source.goals[0]


def load(
    domain_path: str | Path,
    state_path: str | Path,
    goal_text: str | None = None,
    weights: Weights | None = None,
) -> Problem:
    """Read and check a domain and a state; the goal comes from ``goal_text`` or
    the state file. Raises CfgplanError (with every error found) on bad input."""
    sources: dict[str, str] = {}
    domain, text = read_domain(domain_path)
    sources[str(domain_path)] = text
    state, text = read_state(state_path)
    sources[str(state_path)] = text
    goal: Goal | None
    if goal_text is not None:
        sources[GOAL_SOURCE] = f"(goal {goal_text})"
        goal = parse_goal(goal_text)
    else:
        goal = state.goal
    if goal is None:
        raise error(
            f"no goal: {state_path} has no (goal ...) form and --goal was not given",
            hint="add (goal (do-cross-door Pippi Door1)) to the state file, or pass --goal",
        )
    diagnostics = check(domain, state, goal)
    errors = [d for d in diagnostics if d.is_error]
    if errors:
        raise CfgplanError(diagnostics)
    task = compile_task(domain, state, weights)
    return Problem(domain, state, goal, task, sources, [d for d in diagnostics if not d.is_error])
