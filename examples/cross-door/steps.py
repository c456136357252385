"""Implementations for running the cross-door domain as a sequence.

The same as ``impl.py``, whose functionalities it takes, except the action:
here ``cross-door`` takes :data:`CROSSING` calls with the door's pose, then
reports its task accomplished (:data:`cfgplan.runtime.ACHIEVED`), so that a
sequence of configurations goes on to its next step (6.2.2: Pippi crosses,
then Emil)::

    cfgplan run domains/cross-door/domain-steps.lisp \\
        domains/cross-door/state-6.2.2-sequence.lisp \\
        --impl examples/cross-door/steps.py --rate 0 --cycles 400
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from cfgplan.runtime import ACHIEVED, Implementation, current_robot, functionality, load_module

_IMPL = load_module(Path(__file__).with_name("impl.py"))
globals().update(
    {
        name: value
        for name, value in vars(_IMPL).items()
        if isinstance(value, Implementation) and value.name != "cross-door"
    }
)

CROSSING = 100
"""Calls with the door's pose a crossing takes."""

_progress: dict[str, int] = {}


@functionality("cross-door")
def cross_door(door: str, pos: Sequence[float], orient: float) -> object:
    """Record the door's pose relative to the robot (as ``impl.py`` does);
    after :data:`CROSSING` calls the robot is through: the task is accomplished."""
    robot = current_robot()
    _IMPL.RECEIVED.append((robot, door, (pos[0], pos[1]), orient))
    _progress[robot] = _progress.get(robot, 0) + 1
    if _progress[robot] < CROSSING:
        return None
    _progress[robot] = 0
    return ACHIEVED
