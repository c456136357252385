"""What a society runs after a change (5.5, 7.2): the :class:`Decision` the
:class:`~cfgplan.reconfigure.policy.Reconfigurator` answers with, and the
:class:`Hysteresis` that says when a cheaper configuration is worth a switch."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from cfgplan.configuration.model import Configuration
from cfgplan.planner.task import Ground
from cfgplan.reconfigure.switch import Change


@dataclass(frozen=True)
class Hysteresis:
    """When a better configuration is worth a switch, and how failures weigh.

    A running configuration that is still admissible is left for a cheaper one
    only when the cost falls by at least ``max(minimum, margin × cost)``
    (defaults: 1, and 10 %); with the thesis's weights carry-a-bar's return
    from 45 to 33 (12) is worth it, a gain of one channel is not. Recoveries
    themselves are held back on the robots (:mod:`cfgplan.runtime.monitor`).
    """

    margin: float = 0.1
    minimum: float = 1.0
    decay: float = 0.5

    def worth(self, current: float, better: float) -> bool:
        return current - better >= max(self.minimum, self.margin * current) - 1e-9


@dataclass(frozen=True)
class Decision:
    """What the society runs after a change: ``config`` (``None``: nothing)."""

    action: Literal["switch", "stop", "stay"]
    id: int  # the configuration's id after the decision (0: the first one)
    config: Configuration | None
    previous: Configuration | None
    change: Change | None = None
    source: Literal["fallback", "search", ""] = ""
    plan_seconds: float = 0.0
    why: tuple[str, ...] = ()
    withdrawn: tuple[Ground, ...] = ()
    cause: str = ""
