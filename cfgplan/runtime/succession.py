"""Who coordinates once the coordinator is gone: the order of succession (5.5, 7.3).

Every robot that runs the problem derives the same order from it
(:func:`cfgplan.reconfigure.succession.succession_of`): for each step of the
sequence of goals, the robots the remaining goals name, the goal's own robot
first. When the coordinator a robot follows is gone, the first robot of that
order that is alive (and is not the one gone) takes over coordination, one
generation of epochs later (:func:`cfgplan.runtime.protocol.new_epoch`);
every robot fences off the runs of lower generations. Only a robot that
runs the problem with the planner (``cfgplan run --robot``) can take over;
it says so with a liveliness token of its own
(:func:`cfgplan.runtime.keys.planner_key`), so a robot run from emitted
code, which has no planner, is passed over (:func:`candidates`). This
module holds the order as plain names, so that a robot's program needs no
planner to check a claim against it.
"""

from __future__ import annotations

from collections.abc import Collection
from dataclasses import dataclass

__all__ = ["TAKEOVER_AFTER", "Succession", "candidates"]

TAKEOVER_AFTER = 0.25
"""Seconds the next robot of the order waits, once the coordinator's token
went, before it takes over (a token that comes straight back is the same
coordinator, not a death)."""


@dataclass(frozen=True)
class Succession:
    """The order of succession of each step of a sequence (one order for a
    single goal), and how long the next robot waits before it takes over."""

    orders: tuple[tuple[str, ...], ...] = ()
    """``orders[k]``: the robots the goals from step ``k`` on name, in order."""
    after: float = TAKEOVER_AFTER

    def order(self, step: int) -> tuple[str, ...]:
        """The order of succession once the society serves step ``step``."""
        if not self.orders:
            return ()
        return self.orders[max(0, min(step, len(self.orders) - 1))]

    def successor(self, step: int, alive: Collection[str], gone: str) -> str | None:
        """Who takes over from ``gone`` at step ``step``: the first robot of
        the order that is in ``alive`` and is not ``gone``; if none is, the
        first such robot that an earlier goal names (it coordinates a step
        whose robot is lost, until that robot comes back and follows it: a
        goal's robot started again is no coordinator unless it owns the
        first goal, so someone must be); ``None``: no robot the goals name is
        alive."""
        later = self.order(step)
        every = (*later, *(r for r in self.order(0) if r not in later))
        return next((r for r in every if r != gone and r in alive), None)


def candidates(network: object, me: str) -> set[str]:
    """The robots that may take over as ``me`` sees the society on ``network``:
    ``me`` and those alive that say they run its problem with the planner
    (``network.planners()``, their planner tokens): a robot run from emitted
    code has no planner, never takes over, and is passed over in the order.
    A network that does not say who plans (a test's) counts every robot alive."""
    alive = set(getattr(network, "alive", ()))
    planners = getattr(network, "planners", None)
    if planners is not None:
        alive &= planners()
    return alive | {me}
