"""Saying why no configuration is admissible.

Every dead end the search met is kept (first occurrence, in the order met):
method versions whose preconditions no binding satisfies, with the first
failing condition and its bindings (and the fact it nearly matches, when a
constant of it looks like a slip: :func:`cfgplan.planner.ground.why_not`);
channels that end on the wrong robots; and configurations rejected after
expansion (information, cycles, media).
"""

from __future__ import annotations

from typing import Any

from cfgplan.planner.report import Condition, Report


def explain(report: Report, goal: str, limit: int = 40) -> list[str]:
    """Lines for the user: the goal, then each dead end with its place in the domain."""
    if report.undecided:  # the search was stopped: nothing is proved
        lines = [f"no configuration of {goal} found before the search was stopped:"]
    else:
        lines = [f"no admissible configuration for {goal}:"]
    shown = 0
    for dead in report.dead.values():
        where = f" ({dead.span})" if dead.span is not None else ""
        lines.append(f"  {dead.where}{where}: {dead.condition.value}: {dead.reason}")
        shown += 1
        if shown >= limit:
            break
    rejected: dict[tuple[Condition, str], int] = {}
    for dead in report.rejected:
        seen = (dead.condition, dead.describe())
        rejected[seen] = rejected.get(seen, 0) + 1
    for (condition, reason), count in rejected.items():
        times = f" ({count} configurations)" if count > 1 else ""
        lines.append(f"  rejected after expansion{times}: {condition.value}: {reason}")
    hidden = len(report.dead) - shown
    if hidden > 0:
        lines.append(f"  ... and {hidden} more dead ends (--verbose lists them all)")
    if report.undecided:
        lines.append(
            "  one may exist: the dead ends above are only those met so far"
            if len(lines) > 1
            else "  one may exist (a longer --time-limit may find it)"
        )
    elif len(lines) == 1:
        lines.append("  the goal's method has no version")
    if report.status.stopped and report.explaining:
        lines.append("  (the search for dead ends ran out of time: there may be more)")
    return lines


def explanation(report: Report) -> dict[str, Any]:
    """The same as data (``--format json`` when nothing is admissible): every
    dead end with its place, condition, reason, the precondition that failed
    and the bindings it failed under; the rejected configurations by reason."""
    rejected: dict[tuple[Condition, str], int] = {}
    for dead in report.rejected:
        seen = (dead.condition, dead.describe())
        rejected[seen] = rejected.get(seen, 0) + 1
    return {
        "dead_ends": [
            {
                "where": dead.where,
                "condition": dead.condition.value,
                "reason": dead.reason,
                "source": None if dead.span is None else str(dead.span),
                "failed": dead.failed or None,
                "bindings": dict(dead.bindings),
            }
            for dead in report.dead.values()
        ],
        "rejected": [
            {"condition": condition.value, "reason": reason, "configurations": count}
            for (condition, reason), count in rejected.items()
        ],
        "complete": not report.status.stopped,
    }
