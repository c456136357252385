"""An anytime answer: when a search is stopped (``--time-limit``, Ctrl-C)
before it has proven any configuration cheapest, dive depth-first from the
open nodes, cheapest child first (:func:`cfgplan.planner.ranking.place`), to
find *some* admissible configuration. It is marked as not proven optimal.

A plain function over the search's parts: the open nodes, how to expand one
and how to finish a complete one. Its own time is the caller's business
(:mod:`cfgplan.planner.clock`: expanding checks it).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable

from cfgplan.configuration.model import Configuration
from cfgplan.planner.partial import Partial
from cfgplan.planner.ranking import place

Expand = Callable[[Partial], Iterable[tuple[float, Partial]]]
Finish = Callable[[Partial, float], Configuration | None]


def dive(
    frontier: list[tuple[float, Partial]],
    expand: Expand,
    finish: Finish,
    *,
    budget: int = 50_000,
) -> Configuration | None:
    """The first admissible configuration met by a greedy depth-first dive from
    ``frontier`` (best first), within ``budget`` nodes; None when none is met."""
    stack = list(reversed(frontier))  # the best open node on top
    spent = 0
    try:
        while stack and spent < budget:
            total, node = stack.pop()
            spent += 1
            if node.done:
                config = finish(node, total)
                if config is not None:
                    return config.model_copy(update={"proven": False, "derivation": 0})
                continue
            children = sorted(expand(node), key=lambda entry: place(*entry))
            stack.extend(reversed(children))
    except KeyboardInterrupt:
        return None
    return None
