"""Which method instances may occur again in one derivation: the
ones a search remembers for replays (:mod:`cfgplan.planner.replay`). Passes
over the grounder's graph of ground instances (:mod:`cfgplan.planner.graph`),
made once per task and goal (:meth:`cfgplan.planner.grow.Grower`), with the
recursion guard of 4.5 ignored: they over-approximate, which only makes a
search remember more than it replays.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable

from cfgplan.planner.graph import Graph
from cfgplan.planner.task import Ground


def repeatable(
    graph: Graph, roots: Iterable[Ground], least: int = 1, worth: float = 0
) -> frozenset[Ground]:
    """The method instances below ``roots`` that may occur twice in one
    derivation (the recursion guard ignored): below two method items of one
    option's body, or below two roots; and whose derivations may take at
    least ``least`` method expansions (one below itself: any). Only they are
    remembered; none when replays could save fewer than ``worth`` expansions
    in all (each later occurrence of each, at its longest: the thesis's
    build-a-wall, two or three short repeats)."""
    task = graph.grounder.task
    reach: dict[Ground, frozenset[Ground]] = {}

    def below(call: Ground) -> frozenset[Ground]:
        found = reach.get(call)
        if found is None:
            seen = {call}
            todo = [call]
            while todo:
                current = todo.pop()
                for option in graph.instance(current).options:
                    for child in option.children:
                        if child not in seen and task.is_method(child):
                            seen.add(child)
                            todo.append(child)
            found = reach[call] = frozenset(seen)
        return found

    methods = [call for call in roots if task.is_method(call)]
    found: set[Ground] = set()
    _twice(methods, below, found)
    for call in {c for root in methods for c in below(root)}:
        for option in graph.instance(call).options:
            slots = [child for child in option.children if task.is_method(child)]
            if len(slots) > 1:
                _twice(slots, below, found)
    if least > 1 or worth > 0:
        longest = _longest(graph, found)
        found = {call for call in found if longest[call] >= least}
        if worth > 0 and found:
            occurs = _occurrences(graph, methods, {c for root in methods for c in below(root)})
            saved = sum((occurs[call] - 1) * longest[call] for call in found)
            if saved < worth:
                found = set()
    return frozenset(found)


def _occurrences(graph: Graph, roots: list[Ground], calls: set[Ground]) -> dict[Ground, float]:
    """At most how often each of ``calls`` (every method instance below
    ``roots``) occurs in one derivation: once per root, and for each caller,
    as often as the caller times the most the caller's one body holds it
    (infinite on and below a cycle)."""
    task = graph.grounder.task
    most: dict[Ground, dict[Ground, int]] = {}  # caller -> child -> most per body
    waiting = dict.fromkeys(calls, 0)  # callers not yet counted
    for call in calls:
        per: dict[Ground, int] = {}
        for option in graph.instance(call).options:
            counts: dict[Ground, int] = {}
            for child in option.children:
                if task.is_method(child):
                    counts[child] = counts.get(child, 0) + 1
            for child, count in counts.items():
                per[child] = max(per.get(child, 0), count)
        most[call] = per
        for child in per:
            waiting[child] += 1
    occurs: dict[Ground, float] = dict.fromkeys(calls, 0.0)
    for root in roots:
        occurs[root] += 1
    ready = [call for call, count in waiting.items() if count == 0]
    while ready:
        call = ready.pop()
        for child, count in most[call].items():
            occurs[child] += occurs[call] * count
            waiting[child] -= 1
            if waiting[child] == 0:
                ready.append(child)
    for call, count in waiting.items():
        if count:  # on or below a cycle
            occurs[call] = math.inf
    return occurs


def _longest(graph: Graph, calls: Iterable[Ground]) -> dict[Ground, float]:
    """The most method expansions a derivation of each call may take (the
    recursion guard ignored: infinite where an instance is below itself)."""
    task = graph.grounder.task
    longest: dict[Ground, float] = {}
    on_path: set[Ground] = set()
    for start in calls:
        todo: list[tuple[Ground, bool]] = [(start, False)]
        while todo:
            call, ready = todo.pop()
            if call in longest:
                continue
            options = graph.instance(call).options
            children = {c for o in options for c in o.children if task.is_method(c)}
            if not ready:
                on_path.add(call)
                todo.append((call, True))
                for child in children:
                    if child in on_path:
                        longest[call] = math.inf  # below itself
                    elif child not in longest:
                        todo.append((child, False))
                continue
            on_path.discard(call)
            if call in longest:
                continue
            longest[call] = max(
                (
                    1 + sum(longest.get(c, math.inf) for c in o.children if task.is_method(c))
                    for o in options
                ),
                default=1,
            )
    return longest


def _twice(
    slots: list[Ground], below: Callable[[Ground], frozenset[Ground]], found: set[Ground]
) -> None:
    """Add to ``found`` what is below two of ``slots``."""
    once: set[Ground] = set()
    for slot in slots:
        for call in below(slot):
            if call in once:
                found.add(call)
            else:
                once.add(call)
