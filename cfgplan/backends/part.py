"""A robot's wired part as the runtime's plain data (5.3): what ``cfgplan run`` executes.

:func:`runtime_part` turns a :class:`~cfgplan.backends.wiring.RobotPart` into a
:class:`cfgplan.runtime.part.Part` — the same channels and calls the Python
backend writes as code — so that the runtime needs nothing from the planner.
"""

from __future__ import annotations

from cfgplan.backends.wiring import RobotPart
from cfgplan.runtime.part import CallSpec, ChannelSpec, Part

__all__ = ["runtime_part"]


def runtime_part(part: RobotPart, cost: float | None = None) -> Part:
    """``part`` as plain data: channels in order (CH-1 first), calls in sorted
    order; ``cost``, its configuration's, if given (:attr:`Part.cost`)."""
    robot = part.robot
    channels = tuple(
        ChannelSpec(
            ch.kind,
            ch.source,
            ch.target,
            ch.data,
            None
            if ch.kind == "local"
            else (ch.target_robot if ch.source_robot == robot else ch.source_robot),
        )
        for ch in part.individual.channels
    )
    calls = tuple(
        CallSpec(
            c.functionality.label,
            c.functionality.name,
            c.objects,
            c.inputs,
            c.outputs,
            c.freq,
        )
        for c in part.calls
    )
    return Part(robot, channels, calls, cost)
