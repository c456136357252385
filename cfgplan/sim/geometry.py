"""Plane geometry of the simulated world: poses, frames, rectangles, rays.

Poses are ``(x, y, heading)``: metres and radians in the world frame, heading
0 along +x and counter-clockwise positive (the frame is north-aligned, so a
compass reads the world heading, 6.2.1). Ray casting is vectorised with
numpy over every beam and every obstacle at once: a laser scan of 361 beams
against a few dozen segments and discs is one array expression.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

__all__ = [
    "Floats",
    "Pose",
    "Scene",
    "Segment",
    "distance_to_segment",
    "rectangle",
    "relative",
    "wrap",
]

Pose = tuple[float, float, float]
Segment = tuple[float, float, float, float]
Floats = npt.NDArray[np.float64]


def wrap(angle: float) -> float:
    """An angle in [-pi, pi)."""
    return (angle + math.pi) % (2 * math.pi) - math.pi


def relative(observer: Pose, x: float, y: float) -> tuple[float, float]:
    """The point (x, y) in the frame of ``observer``."""
    dx, dy = x - observer[0], y - observer[1]
    c, s = math.cos(observer[2]), math.sin(observer[2])
    return c * dx + s * dy, -s * dx + c * dy


def rectangle(cx: float, cy: float, heading: float, length: float, width: float) -> list[Segment]:
    """The four sides of a rectangle: ``length`` across ``heading``, ``width``
    along it (a wall block whose long faces face ``heading`` and its opposite)."""
    nx, ny = math.cos(heading), math.sin(heading)  # along the short side
    ux, uy = -ny, nx  # along the long side
    corners = [
        (
            cx + su * length / 2 * ux + sn * width / 2 * nx,
            cy + su * length / 2 * uy + sn * width / 2 * ny,
        )
        for su, sn in ((-1, -1), (1, -1), (1, 1), (-1, 1))
    ]
    return [(*corners[i], *corners[(i + 1) % 4]) for i in range(4)]


def distance_to_segment(px: float, py: float, seg: Segment) -> float:
    """Distance from a point to a segment."""
    x1, y1, x2, y2 = seg
    dx, dy = x2 - x1, y2 - y1
    length2 = dx * dx + dy * dy
    t = 0.0 if length2 == 0 else max(0.0, min(1.0, ((px - x1) * dx + (py - y1) * dy) / length2))
    return math.hypot(px - (x1 + t * dx), py - (y1 + t * dy))


@dataclass(frozen=True)
class Scene:
    """What a ray can hit: segments and discs, each with a label index."""

    segments: Floats  # (M, 4)
    segment_labels: npt.NDArray[np.int64]  # (M,)
    discs: Floats  # (K, 3): x, y, radius
    disc_labels: npt.NDArray[np.int64]  # (K,)

    @staticmethod
    def build(
        segments: Sequence[tuple[Segment, int]], discs: Sequence[tuple[float, float, float, int]]
    ) -> Scene:
        seg = np.array([s for s, _ in segments], dtype=np.float64).reshape(-1, 4)
        seg_l = np.array([label for _, label in segments], dtype=np.int64)
        disc = np.array([d[:3] for d in discs], dtype=np.float64).reshape(-1, 3)
        disc_l = np.array([d[3] for d in discs], dtype=np.int64)
        return Scene(seg, seg_l, disc, disc_l)

    def cast(
        self, x: float, y: float, angles: Floats, max_range: float
    ) -> tuple[Floats, npt.NDArray[np.int64]]:
        """Range and label of the first hit of each ray from (x, y) along
        ``angles`` (world radians); ``max_range`` and label -1 for no hit."""
        dx, dy = np.cos(angles), np.sin(angles)
        best = np.full(angles.shape, np.inf)
        label = np.full(angles.shape, -1, dtype=np.int64)
        if len(self.segments):
            px, py = self.segments[:, 0], self.segments[:, 1]
            ex, ey = self.segments[:, 2] - px, self.segments[:, 3] - py
            # origin + t d = p + s e  ->  solve for t, s per (ray, segment)
            denom = dx[:, None] * ey[None, :] - dy[:, None] * ex[None, :]
            wx, wy = px[None, :] - x, py[None, :] - y
            with np.errstate(divide="ignore", invalid="ignore"):
                t = (wx * ey[None, :] - wy * ex[None, :]) / denom
                s = (wx * dy[:, None] - wy * dx[:, None]) / denom
            ok = (np.abs(denom) > 1e-12) & (t >= 0) & (s >= 0) & (s <= 1)
            t = np.where(ok, t, np.inf)
            idx = np.argmin(t, axis=1)
            tmin = t[np.arange(len(angles)), idx]
            better = tmin < best
            best = np.where(better, tmin, best)
            label = np.where(better, self.segment_labels[idx], label)
        if len(self.discs):
            cx, cy, r = self.discs[:, 0] - x, self.discs[:, 1] - y, self.discs[:, 2]
            along = dx[:, None] * cx[None, :] + dy[:, None] * cy[None, :]
            across2 = (cx**2 + cy**2)[None, :] - along**2
            inside = r[None, :] ** 2 - across2
            with np.errstate(invalid="ignore"):
                t = along - np.sqrt(inside)
            t = np.where((inside >= 0) & (t >= 0), t, np.inf)
            idx = np.argmin(t, axis=1)
            tmin = t[np.arange(len(angles)), idx]
            better = tmin < best
            best = np.where(better, tmin, best)
            label = np.where(better, self.disc_labels[idx], label)
        missed = best > max_range
        return np.where(missed, max_range, best), np.where(missed, -1, label)
