"""The naive baseline: the thesis's planner as it describes itself (4.5).

Depth-first over every derivation (each method version, each precondition
binding), collecting every admissible configuration, then sorting by cost;
ties keep the depth-first order (6.3.2). It grows nodes with cfgplan's own
step (:func:`cfgplan.planner.grow.successors`), so that the benchmark
compares search strategies, not two implementations of the step.
"""

from __future__ import annotations

from cfgplan.configuration.model import Configuration
from cfgplan.planner.finish import finish
from cfgplan.planner.ground import Grounder
from cfgplan.planner.grow import successors
from cfgplan.planner.partial import Partial, root
from cfgplan.planner.task import Ground, Task


def enumerate_all(task: Task, goal: Ground) -> list[Configuration]:
    """Every derivation's admissible configuration, cheapest first."""
    grounder = Grounder(task)
    found: list[tuple[float, int, Partial]] = []
    stack: list[Partial] = [root(goal)]
    while stack:
        node = stack.pop()
        if node.done:
            found.append((node.cost, len(found), node))
            continue
        children = [c for c in successors(grounder, node) if isinstance(c, Partial)]
        stack.extend(reversed(children))
    found.sort(key=lambda entry: (entry[0], entry[1]))
    configs: list[Configuration] = []
    for cost, _, node in found:  # admissibility last, configurations built once sorted
        config = finish(node, task, cost)
        if isinstance(config, Configuration):
            configs.append(config.model_copy(update={"derivation": len(configs) + 1}))
    return configs


def distinct(configs: list[Configuration]) -> list[Configuration]:
    """Configurations equal up to labels listed once, first wins."""
    seen: set[object] = set()
    out: list[Configuration] = []
    for config in configs:
        ident = config.identity()
        if ident not in seen:
            seen.add(ident)
            out.append(config)
    return out
