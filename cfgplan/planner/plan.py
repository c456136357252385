"""The planner's entry point: the ``limit`` cheapest admissible configurations.

:func:`plan` puts the parts together: the grounding memo and the bound of the
task (kept per task, so that planning the same task again, e.g. ``-k 1`` then
``--all``, grounds and summarises once), the best-first search, the greedy
dive when the search is stopped before it has proven anything, and a search
without the bound to explain why nothing is admissible when the bound cut
branches before their dead ends were met.
"""

from __future__ import annotations

import time
from weakref import WeakKeyDictionary

from cfgplan.configuration.model import Configuration
from cfgplan.planner.bound import Bound
from cfgplan.planner.dive import dive
from cfgplan.planner.ground import Grounder
from cfgplan.planner.partial import Partial
from cfgplan.planner.partition import Partition
from cfgplan.planner.report import StopReason
from cfgplan.planner.search import BestFirst, Heuristic, Progress
from cfgplan.planner.task import Ground, Task

DIVE_SECONDS = 5.0
"""How long the greedy dive may look for a configuration after a stop."""

_parts: WeakKeyDictionary[Task, tuple[Grounder, Bound, Partition]] = WeakKeyDictionary()


def parts(task: Task) -> tuple[Grounder, Bound, Partition]:
    """The grounding memo and the bounds of ``task``, made once per task."""
    found = _parts.get(task)
    if found is None:
        grounder = Grounder(task)
        found = _parts[task] = (grounder, Bound(task), Partition(grounder))
    return found


def combined(bound: Bound, partition: Partition) -> Heuristic:
    """The larger of the two admissible bounds (a maximum of lower bounds is one)."""

    def estimate(node: Partial) -> float | None:
        first = bound.estimate(node)
        if first is None:
            return None
        second = partition.estimate(node, bound.certain_agents(node))
        return None if second is None else max(first, second)

    return estimate


def _no_bound(node: Partial) -> float:
    return 0.0


def plan(
    task: Task,
    goal: Ground,
    *,
    limit: int | None = 1,
    distinct: bool = True,
    time_limit: float | None = None,
    progress: Progress | None = None,
) -> tuple[list[Configuration], BestFirst]:
    """The ``limit`` cheapest admissible configurations (all when None), and
    the search that found them (its stats, report and stop reason)."""
    grounder, bound, partition = parts(task)
    # Listing everything, a cost estimate cannot stop the search early: then
    # the bound only cuts nodes without completion.
    heuristic = combined(bound, partition) if limit is not None else bound.feasible
    search = BestFirst(grounder, goal, heuristic, distinct, time_limit, progress)
    found: list[Configuration] = []
    try:
        for config in search:
            found.append(config)
            if limit is not None and len(found) >= limit:
                search.stats.complete = False
                break
    except KeyboardInterrupt:
        search.stats.complete = False
        search.stopped = StopReason.INTERRUPTED
    if search.stopped is not None and not found:
        # Stopped before the cheapest was proven: dive for any configuration.
        deadline = time.perf_counter() + DIVE_SECONDS
        guess = dive(search.frontier, search.children, search.finish, deadline=deadline)
        if guess is not None:
            found.append(guess)
    if not found and search.stats.pruned and search.stats.complete:
        # The bound cut branches without meeting their dead ends; search them
        # without it, so the report can say why nothing is admissible.
        explaining = BestFirst(grounder, goal, _no_bound, distinct, time_limit)
        for _ in explaining:
            break
        search.report = explaining.report
    return found, search
