"""An anytime answer: when the best-first search is stopped (``--time-limit``,
Ctrl-C) before it has proven any configuration cheapest, dive depth-first from
the open nodes, cheapest child first, to find *some* admissible configuration.
It is marked as not proven optimal.
"""

from __future__ import annotations

import time
from typing import TYPE_CHECKING

from cfgplan.configuration.model import Configuration

if TYPE_CHECKING:
    from cfgplan.planner.search import Search


def dive(search: Search, budget: int = 50_000, seconds: float = 5.0) -> Configuration | None:
    """The first admissible configuration met by a greedy depth-first dive,
    within ``budget`` nodes and ``seconds``; None when none is met."""
    deadline = time.perf_counter() + seconds
    stack = list(reversed(search.frontier))  # the best open node on top
    spent = 0
    try:
        while stack and spent < budget and time.perf_counter() < deadline:
            total, node = stack.pop()
            spent += 1
            if node.done:
                config = search.finished(node, total)
                if config is not None:
                    return config.model_copy(update={"proven": False, "derivation": 0})
                continue
            children = sorted(search.children(node), key=lambda entry: (entry[0], entry[1].path))
            stack.extend(reversed(children))
    except KeyboardInterrupt:
        return None
    return None
