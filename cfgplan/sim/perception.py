"""Perception for the bundled implementations: what a scan says about objects,
and where a robot is on its map.

Everything here works on readings and on what a robot knows in advance (its
map, the sizes of blocks), never on the world's state:

* :func:`runs` — the beams of a scan that hit one object, in beam order,
  with whether each end of the run is the object's own silhouette (the next
  beam goes past it) or hidden (the next beam hits something nearer);
* :func:`faces` — a run split into straight faces (the sides of a block);
* :func:`long_face` — the longest face, if it is a long side of a block or a
  wall: its line and the normal pointing away from the observer;
* :func:`block`, :func:`free_end` — a block's centre and orientation, and a
  built wall's free-end corner, from its faces and the ends of them that are
  true corners;
* :func:`localize` — a pose from odometry and ranges matched to the map
  (Gauss–Newton on the ranges, the odometry as a prior).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import numpy as np

from cfgplan.sim.geometry import Scene, Segment, wrap

__all__ = [
    "Face",
    "Run",
    "Seen",
    "block",
    "faces",
    "free_end",
    "localize",
    "long_face",
    "runs",
    "square",
]

SPLIT = 0.03
"""Metres a point may stray from a face's line before the face is split."""


@dataclass(frozen=True)
class Run:
    """Consecutive beams that hit one object: their points (robot frame)."""

    first: int  # beam index
    last: int
    points: tuple[tuple[float, float], ...]
    open_start: bool  # the beam before the run goes past the object (a silhouette)
    open_end: bool
    hidden_by: tuple[str | None, str | None]  # what hides each end, if hidden
    beside: tuple[float | None, float | None] = (None, None)
    """The range of the beam before and after the run (``None``: no echo, or
    no such beam)."""


@dataclass(frozen=True)
class Face:
    """A straight face: a point on it, its direction, and the normal pointing
    away from the observer (into the object)."""

    x: float
    y: float
    ux: float
    uy: float
    points: tuple[tuple[float, float], ...]

    @property
    def normal(self) -> tuple[float, float]:
        nx, ny = -self.uy, self.ux
        return (nx, ny) if nx * self.x + ny * self.y > 0 else (-nx, -ny)

    def along(self, px: float, py: float) -> float:
        return (px - self.x) * self.ux + (py - self.y) * self.uy

    @property
    def span(self) -> tuple[float, float]:
        s = [self.along(*p) for p in self.points]
        return min(s), max(s)

    @property
    def length(self) -> float:
        lo, hi = self.span
        return hi - lo

    def at(self, s: float) -> tuple[float, float]:
        return self.x + s * self.ux, self.y + s * self.uy

    def meets(self, ox: float, oy: float, dx: float, dy: float) -> tuple[float, float] | None:
        """Where the ray from (ox, oy) along (dx, dy) crosses this face's line."""
        denom = dx * self.uy - dy * self.ux
        if abs(denom) < 1e-9:
            return None
        t = ((self.x - ox) * self.uy - (self.y - oy) * self.ux) / denom
        return (ox + t * dx, oy + t * dy) if t > 0 else None


def _angle(scan: dict[str, Any], i: int) -> float:
    return float(scan["start"]) + i * float(scan["step"])


def runs(scan: dict[str, Any], name: str) -> list[Run]:
    """The runs of beams that hit ``name``, in beam order."""
    ranges: list[float] = scan["ranges"]
    hits: list[str | None] = scan["hits"]
    out: list[Run] = []
    i, n = 0, len(ranges)
    while i < n:
        if hits[i] != name:
            i += 1
            continue
        j = i
        while j + 1 < n and hits[j + 1] == name:
            j += 1
        points = tuple(
            (ranges[k] * math.cos(_angle(scan, k)), ranges[k] * math.sin(_angle(scan, k)))
            for k in range(i, j + 1)
        )
        before = _beyond(scan, i, i - 1)
        after = _beyond(scan, j, j + 1)
        beside = (_echo(scan, i - 1), _echo(scan, j + 1))
        out.append(Run(i, j, points, before[0], after[0], (before[1], after[1]), beside))
        i = j + 1
    return out


def _beyond(scan: dict[str, Any], end: int, nxt: int) -> tuple[bool, str | None]:
    """Whether the beam next to a run's end goes past the object (True), or
    what nearer thing hides the rest (False, its name); the edge of the field
    of view hides it too (False, None)."""
    ranges: list[float] = scan["ranges"]
    hits: list[str | None] = scan["hits"]
    if not 0 <= nxt < len(ranges):
        return False, None
    if hits[nxt] is None or ranges[nxt] > ranges[end] + 0.05:
        return True, None
    return False, hits[nxt]


def _echo(scan: dict[str, Any], i: int) -> float | None:
    if not 0 <= i < len(scan["ranges"]) or scan["hits"][i] is None:
        return None
    return float(scan["ranges"][i])


def _fit(points: Sequence[tuple[float, float]]) -> Face:
    """The line through ``points`` by least squares (the principal axis of
    their scatter, in closed form)."""
    n = len(points)
    mx = sum(p[0] for p in points) / n
    my = sum(p[1] for p in points) / n
    sxx = sum((p[0] - mx) ** 2 for p in points)
    syy = sum((p[1] - my) ** 2 for p in points)
    sxy = sum((p[0] - mx) * (p[1] - my) for p in points)
    angle = 0.5 * math.atan2(2 * sxy, sxx - syy)
    return Face(mx, my, math.cos(angle), math.sin(angle), tuple(points))


@lru_cache(maxsize=256)
def faces(run: Run, split: float = SPLIT) -> list[tuple[int, int, Face]]:
    """The run split into straight faces: (first index, last index, face) of
    three points or more, in beam order. Split where a point strays more than
    ``split`` from the chord (recursively), then neighbours that lie on one
    line are merged again (noise splits a face; a corner does not merge)."""
    pts = run.points
    pieces: list[tuple[int, int]] = []
    todo = [(0, len(pts) - 1)]
    while todo:
        a, b = todo.pop()
        if b - a < 2:
            pieces.append((a, b))
            continue
        (x1, y1), (x2, y2) = pts[a], pts[b]
        length = math.hypot(x2 - x1, y2 - y1) or 1e-9
        dev = [
            abs((x2 - x1) * (y1 - py) - (x1 - px) * (y2 - y1)) / length for px, py in pts[a : b + 1]
        ]
        k = int(np.argmax(dev))
        if dev[k] > split and 0 < k < b - a:
            todo += [(a + k, b), (a, a + k)]
        else:
            pieces.append((a, b))
    pieces.sort()
    merged: list[tuple[int, int]] = []
    for a, b in pieces:
        if merged and _straight(pts[merged[-1][0] : b + 1], split):
            merged[-1] = (merged[-1][0], b)
        else:
            merged.append((a, b))
    return [(run.first + a, run.first + b, _fit(pts[a : b + 1])) for a, b in merged if b - a >= 2]


def _straight(points: Sequence[tuple[float, float]], split: float) -> bool:
    """Whether ``points`` lie on one line, within ``split``."""
    if len(points) < 3:
        return True
    f = _fit(points)
    nx, ny = -f.uy, f.ux
    return max(abs((x - f.x) * nx + (y - f.y) * ny) for x, y in points) <= split


def long_face(run: Run, thickness: float) -> tuple[int, int, Face] | None:
    """The longest face of the run if it is longer than the object is thick
    (a long side), else ``None``."""
    found = faces(run)
    if not found:
        return None
    best = max(found, key=lambda f: f[2].length)
    return best if best[2].length > thickness + 0.05 else None


def square(angle: float) -> float:
    """An object's orientation given as the normal of its long faces, which
    could be either: the one within a quarter turn of the observer's heading."""
    a = wrap(angle)
    if a > math.pi / 2:
        a -= math.pi
    elif a <= -math.pi / 2:
        a += math.pi
    return a


def _corner(
    scan: dict[str, Any], run: Run, face: tuple[int, int, Face], at_start: bool
) -> tuple[float, float] | None:
    """The corner at one end of ``face`` if it is a true corner of the object:
    where it meets the next face of the run, or between the face's last beam
    and the next one when that beam goes past the object or hits another of
    its faces (too few points for a line); else ``None`` (hidden)."""
    first, last, f = face
    edge = first if at_start else last
    inside = first > run.first if at_start else last < run.last
    if inside:
        others = [x for x in faces(run) if x[2] is not f]
        nxt = [x for x in others if (x[1] <= first if at_start else x[0] >= last)]
        if nxt:
            g = (max if at_start else min)(nxt, key=lambda x: x[0])[2]
            denom = f.ux * g.uy - f.uy * g.ux
            if abs(denom) > 0.3:  # not nearly parallel: a corner
                t = ((g.x - f.x) * g.uy - (g.y - f.y) * g.ux) / denom
                return f.at(t)
    elif not (run.open_start if at_start else run.open_end) and not _ends_there(
        scan, run, f, at_start
    ):
        return None
    mid = _angle(scan, edge) + (-0.5 if at_start else 0.5) * float(scan["step"])
    return f.meets(0.0, 0.0, math.cos(mid), math.sin(mid))


def _ends_there(scan: dict[str, Any], run: Run, f: Face, at_start: bool) -> bool:
    """Whether the nearer echo next to a run's end lies (almost) on the face's
    line extended, or beyond it: then the face ended there, nothing hides it."""
    nxt = run.first - 1 if at_start else run.last + 1
    echo = run.beside[0 if at_start else 1]
    if echo is None or not 0 <= nxt < len(scan["ranges"]):
        return False
    a = _angle(scan, nxt)
    on_line = f.meets(0.0, 0.0, math.cos(a), math.sin(a))
    return on_line is not None and echo >= math.hypot(*on_line) - 0.05


@dataclass(frozen=True)
class Seen:
    """What a scan tells of a block of known size: its centre and the normal
    of its long sides (robot frame), each ``None`` when it cannot be told."""

    centre: tuple[float, float] | None
    normal: float | None
    why: str


def block(scan: dict[str, Any], name: str, size: tuple[float, float]) -> Seen:
    """A block's centre and orientation from its faces in the scan: a long
    side with a true corner at an end (the centre is half a length along it
    and half a thickness in), or whole; a short side seen whole (the centre
    is half a length behind it)."""
    length, thickness = size
    found = [r for r in runs(scan, name) if len(r.points) >= 3]
    if not found:
        return Seen(None, None, f"{name} not in view")
    centres: list[tuple[float, float]] = []
    normal: float | None = None
    seen = [(run, face) for run in found for face in faces(run)]
    seen.sort(key=lambda x: -x[1][2].length)  # the longest side gives the orientation
    for run, face in seen:
        f = face[2]
        nx, ny = f.normal
        lo, hi = f.span
        corners = [_corner(scan, run, face, at_start) for at_start in (True, False)]
        if f.length > thickness + 0.05:  # a long side
            if normal is None:
                normal = math.atan2(ny, nx)
            for corner in corners:
                if corner is None:
                    continue
                s = f.along(*corner)
                s += -length / 2 if abs(s - hi) < abs(s - lo) else length / 2
                x, y = f.at(s)
                centres.append((x + nx * thickness / 2, y + ny * thickness / 2))
            if not any(corners) and f.length > length - 0.04:
                x, y = f.at((lo + hi) / 2)
                centres.append((x + nx * thickness / 2, y + ny * thickness / 2))
        elif all(corners) and abs(f.length - thickness) < 0.05:  # a short side, whole
            if normal is None:
                normal = math.atan2(ny, nx) + math.pi / 2
            x, y = f.at((lo + hi) / 2)
            centres.append((x + nx * length / 2, y + ny * length / 2))
    if not centres:
        return Seen(None, normal, f"no corner of {name} in view")
    cx = sum(c[0] for c in centres) / len(centres)
    cy = sum(c[1] for c in centres) / len(centres)
    return Seen((cx, cy), normal, "")


def free_end(
    scan: dict[str, Any], name: str, thickness: float, side: str
) -> tuple[float, float] | str:
    """The corner of a built wall's face at its free end (``left`` or
    ``right`` seen along the face's normal), or why it cannot be seen."""
    found = [r for r in runs(scan, name) if len(r.points) >= 3]
    if not found:
        return f"{name} not in view"
    run = max(found, key=lambda r: len(r.points))
    face = long_face(run, thickness)
    if face is None:
        return f"no long side of {name} in view"
    f = face[2]
    nx, ny = f.normal
    fx, fy = (-ny, nx) if side == "left" else (ny, -nx)
    # which end of the face lies towards the free end
    first_pt, last_pt = f.points[0], f.points[-1]
    at_start = first_pt[0] * fx + first_pt[1] * fy > last_pt[0] * fx + last_pt[1] * fy
    corner = _corner(scan, run, face, at_start)
    if corner is None:
        hidden = run.hidden_by[0 if at_start else 1]
        if hidden is None:
            return f"the free end of {name} is out of the field of view"
        return f"the free end of {name} is hidden behind {hidden}"
    return corner


def localize(
    guess: tuple[float, float, float],
    scan: dict[str, Any],
    walls: Sequence[Segment],
    prior: tuple[float, float] = (0.3, 0.15),
    iterations: int = 4,
) -> tuple[float, float, float]:
    """The pose whose expected ranges on the map best match the scan's echoes
    of walls, starting from (and held to) ``guess``: Gauss–Newton on the
    ranges, ``prior`` the deviations (metres, radians) of the guess."""
    if not walls:
        return guess
    scene = Scene.build([(w, 0) for w in walls], [])
    ranges = np.array(scan["ranges"], dtype=np.float64)
    hits = scan["hits"]
    use = np.array([h == "wall" for h in hits])
    if use.sum() < 3:
        return guess
    rel = float(scan["start"]) + float(scan["step"]) * np.arange(len(ranges))
    max_range = float(scan["max_range"])
    sigma = 0.03
    weights = np.array([1 / prior[0] ** 2, 1 / prior[0] ** 2, 1 / prior[1] ** 2])
    p = np.array(guess, dtype=np.float64)
    g = p.copy()

    def expected(q: np.ndarray) -> np.ndarray:
        r, _ = scene.cast(float(q[0]), float(q[1]), q[2] + rel, max_range + 1.0)
        return r

    for _ in range(iterations):
        e0 = expected(p)
        ok = use & (np.abs(ranges - e0) < 0.4) & (e0 < max_range)
        if ok.sum() < 3:
            break
        jac = np.zeros((len(ranges), 3))
        for k, eps in enumerate((1e-3, 1e-3, 1e-3)):
            q = p.copy()
            q[k] += eps
            jac[:, k] = (expected(q) - e0) / eps
        j = jac[ok]
        r = (ranges - e0)[ok]
        delta_prior = g - p
        delta_prior[2] = wrap(float(delta_prior[2]))
        h = j.T @ j / sigma**2 + np.diag(weights)
        b = j.T @ r / sigma**2 + weights * delta_prior
        step = np.linalg.solve(h, b)
        p = p + step
        if np.abs(step).max() < 1e-4:
            break
    return float(p[0]), float(p[1]), wrap(float(p[2]))
