"""The naive baseline: the thesis's planner as it describes itself (4.5).

Depth-first over every derivation (each method version, each precondition
binding), collecting every admissible configuration, then sorting by cost;
ties keep the depth-first order (6.3.2). It shares the expansion step with
cfgplan (``cfgplan.planner.partial``) so that the benchmark compares search
strategies, not two implementations of the step.
"""

from __future__ import annotations

from cfgplan.configuration.model import Configuration
from cfgplan.planner.complete import finish
from cfgplan.planner.match import bind_name, bindings
from cfgplan.planner.partial import (
    Dead,
    Partial,
    expand_method,
    instantiate,
    place_functionality,
    root,
)
from cfgplan.planner.search import Report
from cfgplan.planner.task import Ground, Task


def enumerate_all(task: Task, goal: Ground) -> list[Configuration]:
    """Every derivation's admissible configuration, cheapest first."""
    found: list[tuple[float, int, Partial]] = []
    report = Report()
    stack: list[Partial] = [root(goal)]
    while stack:
        node = stack.pop()
        if node.done:
            found.append((node.cost, len(found), node))
            continue
        item = node.stack[0]
        sig = (item.call[0], len(item.call) - 1)
        children: list[Partial] = []
        if sig in task.methods:
            if item.call in item.ancestors:
                continue
            choice = 0
            for method in task.methods[sig]:
                env = bind_name(method.params, item.call[1:])
                if env is None:
                    continue
                for env2 in bindings(task, method.tests, env):
                    expansion = instantiate(method, env2, "")
                    child = (
                        expansion
                        if isinstance(expansion, Dead)
                        else expand_method(node, item, expansion, "", None, choice)
                    )
                    choice += 1
                    if not isinstance(child, Dead):
                        children.append(child)
        else:
            schema = task.functionalities[sig]
            if item.call in node.labels:
                reused = place_functionality(node, item, schema, None, None, task)
                if not isinstance(reused, Dead):
                    children.append(reused)
            else:
                env = bind_name(schema.params, item.call[1:])
                options = [] if env is None else list(bindings(task, schema.tests, env))
                for index, env2 in enumerate(options):
                    branch = index if len(options) > 1 else None
                    child = place_functionality(node, item, schema, env2, branch, task)
                    if not isinstance(child, Dead):
                        children.append(child)
        stack.extend(reversed(children))
    found.sort(key=lambda entry: (entry[0], entry[1]))
    configs: list[Configuration] = []
    for cost, _, node in found:  # admissibility last, configurations built once sorted
        config = finish(node, task, cost, report)
        if config is not None:
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
