"""Who coordinates a society: the goal's robot, and who may take over (5.5, 7.3).

The robot that owns the goal coordinates (:func:`coordinator_of`): it plans,
and every other robot follows it, running the part it is sent; when it is
gone, a robot the remaining goals name takes over (:func:`succession_of`).
:func:`owner` tells, from the problem alone (no search), which robot the
coordinator is where the goal's method says, and :func:`never_coordinates`
which robots follow from start to end: they need no plan (``cfgplan run
--robot`` plans nothing for them and loads no search) and watch only the
robots that coordinate — a society of 50 robots started together spends
its CPU on 50 planners otherwise, and each loss wakes all 50.

:func:`coordinators_of` says which robots may coordinate at all (the
society's keys), :func:`succession_of` the order in which they take over.
"""

from __future__ import annotations

from collections.abc import Collection, Sequence
from typing import TYPE_CHECKING, Any

from cfgplan.planner.task import Ground, Task
from cfgplan.planner.unify import bind_name
from cfgplan.runtime.succession import TAKEOVER_AFTER, Succession

if TYPE_CHECKING:
    from cfgplan.configuration.model import Configuration

__all__ = [
    "certain_agents",
    "coordinator_of",
    "coordinators_of",
    "never_coordinates",
    "owner",
    "succession_of",
]


def coordinator_of(goal: Ground, config: Configuration | None) -> str:
    """The robot that owns the goal: its first argument that is an agent of
    the configuration (``do-cross-door(Emil, Door1)``: Emil), else the
    configuration's first agent, else the goal's first argument."""
    agents = [] if config is None else config.agents
    for arg in goal[1:]:
        if arg in agents:
            return arg
    if agents:
        return agents[0]
    return goal[1] if len(goal) > 1 else goal[0]


def certain_agents(task: Task, goal: Ground) -> frozenset[str]:
    """The agents every configuration for ``goal`` places a functionality on,
    as far as the goal's own method says: in every version of it that the
    goal's arguments bind, a functionality of its body runs there
    (``do-dock(Vacu, Charger1)``: each version calls ``dock(?r, ?s)``, which
    runs on Vacu). Empty when the method has no such version (what its
    sub-methods place is not looked at)."""
    versions = task.methods.get((goal[0], len(goal) - 1), ())
    found: frozenset[str] | None = None
    for method in versions:
        env = bind_name(method.params, goal[1:])
        if env is None:
            continue  # this version does not apply to the goal
        here = set()
        for _, call in method.body:
            if len(call) > 1 and (call[0], len(call) - 1) in task.functionalities:
                where = env.get(call[1], call[1])
                if where[:1] != "?" and where in task.agents:
                    here.add(where)
        found = frozenset(here) if found is None else found & here
    return found or frozenset()


def owner(task: Task, goal: Ground) -> str | None:
    """The goal's coordinator whatever configuration is planned, told without
    planning, or ``None`` when only a plan tells: the coordinator is the
    goal's first argument that the configuration runs on
    (:func:`coordinator_of`), so where every configuration runs on the first
    argument (:func:`certain_agents`: ``do-dock(Vacu, Charger1)``, whose
    every version runs ``dock`` on Vacu), it is that argument."""
    if len(goal) > 1 and goal[1] in certain_agents(task, goal):
        return goal[1]
    return None


def never_coordinates(task: Task, goals: Sequence[Ground], robot: str) -> bool:
    """Whether ``robot`` never coordinates the society that serves ``goals``,
    told without planning: the first goal's coordinator is known
    (:func:`owner`) and is another robot, and no goal names ``robot``, so no
    order of succession holds it (:func:`succession_of`). Such a robot
    follows from start to end: it needs no plan of its own."""
    if not goals or owner(task, goals[0]) in (None, robot):
        return False
    return all(robot not in goal[1:] for goal in goals)


def coordinators_of(transport: Any, members: frozenset[str]) -> frozenset[str]:
    """The robots that may coordinate ``transport``'s society: with its keys,
    those its ``society.json`` marks so (only they may send switches); without,
    any robot of the state."""
    folder = getattr(getattr(transport, "options", None), "keys", None)
    if not folder:
        return members
    from cfgplan.security.zenoh_tls import society_of

    keys = society_of(folder)
    return frozenset(m.name for m in keys.robots if m.coordinator)


def succession_of(
    goals: Sequence[Ground],
    agents: Collection[str],
    may: Collection[str] | None = None,
    after: float = TAKEOVER_AFTER,
) -> Succession:
    """The order of succession of each step of ``goals``: the robots of
    ``agents`` (and of ``may``, those that may coordinate, if given) that the
    goals from that step on name, in the order they are named."""
    orders: list[tuple[str, ...]] = []
    for step in range(len(goals)):
        named: list[str] = []
        for goal in goals[step:]:
            for arg in goal[1:]:
                if arg in agents and (may is None or arg in may) and arg not in named:
                    named.append(arg)
        orders.append(tuple(named))
    return Succession(tuple(orders), after)
