"""A planning problem: domain, state and goal read, checked and compiled.

This is the front of the pipeline every command shares (read -> check ->
compile); the planner and the backends take it from here.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

from cfgplan.check import check
from cfgplan.configuration.cost import Weights
from cfgplan.diagnostics import CfgplanError, Diagnostic, error
from cfgplan.ir.model import Domain, Goal, Span, State
from cfgplan.notation import atom_text
from cfgplan.planner.task import Ground, Task, compile_task, pattern
from cfgplan.syntax.reader import collection_paused, parse, read_domain, read_state

GOAL_SOURCE = "--goal"


@dataclass(eq=False, repr=False)
class Problem:
    """Everything needed to plan: the domain, the state, the goals, the compiled task."""

    domain: Domain
    state: State
    goal: Goal
    task: Task
    warnings: list[Diagnostic] = field(default_factory=list)
    goals: tuple[Goal, ...] = ()
    """Every goal, in order: more than one for a sequence of configurations."""

    def __post_init__(self) -> None:
        if not self.goals:
            self.goals = (self.goal,)

    @property
    def goal_call(self) -> Ground:
        return pattern(self.goal.call)

    @property
    def goal_calls(self) -> tuple[Ground, ...]:
        return tuple(pattern(g.call) for g in self.goals)


def parse_goal(text: str, line: int = 1) -> Goal:
    """A goal given on the command line: ``(do-cross-door Pippi Door1)`` or
    ``do-cross-door(Pippi, Door1)``; ``line`` is its place among several
    ``--goal`` options (messages quote that line of them)."""
    if "(" not in text:  # words without parentheses, or nothing
        start = 7  # the goal is quoted as "(goal TEXT)"
        span = Span(
            file=GOAL_SOURCE, line=line, column=start, end_line=line, end_column=start + len(text)
        )
        words = " ".join(text.split())
        if not words:
            raise error("the goal is empty", span, "write --goal '(METHOD ARGUMENT ...)'")
        raise error(
            "a goal is a method instance in parentheses",
            span,
            f"add the parentheses: --goal '({words})'",
        )
    from cfgplan.syntax.unexpected import unclosed  # --goal only: not on plan's common path

    open_at = unclosed(text)
    if open_at is not None:  # else "(goal " would be the '(' never closed
        column = open_at[1] + len("(goal ")
        raise error(
            "a list is not closed (missing ')')",
            Span(file=GOAL_SOURCE, line=line, column=column, end_line=line, end_column=column + 1),
            "every '(' needs a matching ')': this one is never closed",
        )
    wrapped = "\n" * (line - 1) + f"(goal {text})"
    source = parse(wrapped, GOAL_SOURCE)
    if len(source.goals) != 1:
        span = Span(file=GOAL_SOURCE, line=line, column=1, end_line=line, end_column=1)
        raise error("expected one method instance such as (do-cross-door Pippi Door1)", span)
    return source.goals[0]


def example_goal(domain: Domain) -> str:
    """A goal of ``domain`` to show in a hint: its first method no other method
    calls (the top of a hierarchy), its parameters as placeholders in capitals."""
    called = {item.call.signature for m in domain.methods for item in m.body}
    tops = [m for m in domain.methods if m.name.signature not in called] or list(domain.methods)
    if not tops:
        return "(METHOD ARGUMENT ...)"
    name = tops[0].name
    return atom_text([name.predicate, *(a.lstrip("?").upper() for a in name.args)])


def load(
    domain_path: str | Path,
    state_path: str | Path,
    goal_text: str | Sequence[str] | None = None,
    weights: Weights | None = None,
) -> Problem:
    """Read and check a domain and a state. The goals come from ``goal_text``
    (one, or several for a sequence), else from the state file's ``(goal ...)``
    or ``(sequence ...)``. Raises CfgplanError (with every error found) on bad input."""
    with collection_paused():  # reading, checking and compiling make many young objects
        domain, _ = read_domain(domain_path)
        state, _ = read_state(state_path)
        texts = [goal_text] if isinstance(goal_text, str) else list(goal_text or [])
        goals: tuple[Goal, ...]
        if texts:
            goals = tuple(parse_goal(t, line) for line, t in enumerate(texts, 1))
        else:
            goals = (state.goal,) if state.goal is not None else state.sequence
        if not goals:
            raise error(
                f"no goal: {state_path} has no (goal ...) form and --goal was not given",
                hint=f"add (goal {example_goal(domain)}) to the state file, or pass --goal",
            )
        diagnostics: list[Diagnostic] = []
        for goal in goals:
            diagnostics += [d for d in check(domain, state, goal) if d not in diagnostics]
        errors = [d for d in diagnostics if d.is_error]
        if errors:
            raise CfgplanError(diagnostics)
        task = compile_task(domain, state, weights)
        warnings = [d for d in diagnostics if not d.is_error]
        return Problem(domain, state, goals[0], task, warnings, goals)
