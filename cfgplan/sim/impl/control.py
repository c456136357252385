"""Small motion controllers the bundled actions share."""

from __future__ import annotations

import math

__all__ = ["clip", "steer"]


def clip(value: float, limit: float) -> float:
    return max(-limit, min(limit, value))


def steer(x: float, y: float, top: float, turn: float = 1.2) -> tuple[float, float]:
    """Speed and turn rate that take a unicycle to the point (x, y) of its
    own frame: turn towards it, and go forward only when roughly facing it,
    slowing down as it comes near."""
    distance = math.hypot(x, y)
    bearing = math.atan2(y, x)
    w = clip(2.0 * bearing, turn)
    facing = max(0.0, math.cos(bearing))
    v = min(top, 0.8 * distance) * facing**3 if abs(bearing) < math.pi / 2 else 0.0
    return v, w
