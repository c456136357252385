"""The simulated world of chapter 6: rooms, doors, robots, a bar, blocks.

The map is the rooms' outlines (6.2.1: two 3 m rooms and a door) with the
doors cut out, plus any obstacles; the world advances by :meth:`World.step`
in fixed steps of simulated time (each split into short sub-steps for the
physics), applies the scenario's world changes when they fall due, and keeps
every body's trajectory. Randomness comes from one seed: each robot's each
sensor and its wheels draw from a stream of their own (seeded by the seed and
their names), so that adding a sensor does not change another's noise.

Implementations never see this object: they get their robot's sensors and
motors through :mod:`cfgplan.sim.onboard`.
"""

from __future__ import annotations

import math
import random
from dataclasses import dataclass, field
from typing import Any

from shapely.geometry import MultiLineString, Point, Polygon

from cfgplan.sim.blocks import BlockState, attach, push
from cfgplan.sim.bodies import Body
from cfgplan.sim.geometry import (
    Pose,
    Scene,
    Segment,
    distance_to_segment,
    rectangle,
    wrap,
)
from cfgplan.sim.scenario import Door, Magnetic, Scenario, WallObject, parse_sensor, room_of

__all__ = ["SUBSTEP", "Sample", "World", "map_segments"]

SUBSTEP = 0.02
"""Seconds of one physics sub-step."""


@dataclass(frozen=True)
class Sample:
    """The world at one step: every robot's and block's pose, the bar's length."""

    t: float
    robots: dict[str, Pose]
    blocks: dict[str, Pose]
    bar: float | None


@dataclass
class World:
    """The true state of the simulation (see the module docstring)."""

    scenario: Scenario
    seed: int
    time: float = 0.0
    steps: int = 0
    bodies: dict[str, Body] = field(default_factory=dict)
    blocks: dict[str, BlockState] = field(default_factory=dict)
    walls: dict[str, WallObject] = field(default_factory=dict)
    doors: dict[str, Door] = field(default_factory=dict)
    magnetic: list[Magnetic] = field(default_factory=list)
    segments: list[Segment] = field(default_factory=list)
    changes: list[tuple[float, str]] = field(default_factory=list)
    """World changes applied: (time, what)."""
    samples: list[Sample] = field(default_factory=list)
    bar_dropped: tuple[float, float] | None = None  # (time, distance)
    labels: list[str] = field(default_factory=list)
    memories: dict[tuple[str, str], dict[str, Any]] = field(default_factory=dict)
    """Implementations' state between calls, per robot (:meth:`Hardware.memory`)."""
    _streams: dict[tuple[str, str], random.Random] = field(default_factory=dict)
    _pending: list[int] = field(default_factory=list)
    _walls: MultiLineString = field(default_factory=MultiLineString)

    def __post_init__(self) -> None:
        s = self.scenario
        self.segments = map_segments(s)
        self._walls = MultiLineString([[w[:2], w[2:]] for w in self.segments])
        self.doors = dict(s.world.doors)
        self.walls = dict(s.world.walls)
        self.magnetic = list(s.world.magnetic)
        for name, spec in s.robots.items():
            x, y, heading = spec.at or (0.0, 0.0, 0.0)  # a pusher is placed at its block
            self.bodies[name] = Body(
                name,
                (x, y, wrap(math.radians(heading))),
                s.motion,
                s.sensor(name, "odometry"),
                self.rng(name, "wheels"),
            )
        for name, block_spec in s.world.blocks.items():
            x, y = block_spec.at
            block = BlockState(name, block_spec, (x, y, wrap(math.radians(block_spec.heading))))
            self.blocks[name] = block
            attach(block, self.bodies)
        self.labels = ["wall", *self.walls, *self.blocks, *self.bodies]
        self._pending = sorted(range(len(s.events)), key=lambda i: (s.events[i].at, i))
        self._sample()

    # -- time -----------------------------------------------------------------

    def clock(self) -> float:
        """The simulated time, in seconds: the robots' clock."""
        return self.time

    def rng(self, owner: str, what: str) -> random.Random:
        """The random stream of ``owner``'s ``what`` (seeded by the seed and the names)."""
        key = (owner, what)
        found = self._streams.get(key)
        if found is None:
            found = self._streams[key] = random.Random(f"{self.seed}:{owner}:{what}")
        return found

    def step(self, dt: float) -> None:
        """Advance by ``dt`` seconds: world changes due, motion, the bar."""
        self._events()
        n = max(1, math.ceil(dt / SUBSTEP - 1e-9))
        h = dt / n
        start = self.time
        for i in range(n):
            self.time = start + i * h
            for body in self.bodies.values():
                if body.attached is None:
                    self._move(body, h)
            for block in self.blocks.values():
                push(self, block, h)
            self._bar()
        self.steps += 1
        self.time = round(self.steps * dt, 9)
        self._sample()

    def _events(self) -> None:
        events = self.scenario.events
        while self._pending and events[self._pending[0]].at <= self.time + 1e-9:
            event = events[self._pending.pop(0)]
            if event.breaks is not None:
                parsed = parse_sensor(event.breaks)
                if parsed is not None:
                    self.bodies[parsed[1]].broken.add(parsed[0])
                    self.changes.append((self.time, f"{parsed[0]}({parsed[1]}) breaks"))
            elif event.repair is not None:
                parsed = parse_sensor(event.repair)
                if parsed is not None:
                    self.bodies[parsed[1]].broken.discard(parsed[0])
                    self.changes.append((self.time, f"{parsed[0]}({parsed[1]}) repaired"))
            elif event.magnetic is not None:
                m = event.magnetic.model_copy(update={"start": max(event.magnetic.start, event.at)})
                self.magnetic.append(m)
                self.changes.append(
                    (self.time, f"magnetic disturbance at {m.at[0]:g}, {m.at[1]:g}")
                )

    # -- motion ----------------------------------------------------------------

    def _move(self, body: Body, h: float) -> None:
        v, w = body.executed(self.time, h)
        if v == 0.0 and w == 0.0:
            return
        x, y, th = body.pose
        mid = th + w * h / 2
        turned = wrap(th + w * h)
        moved = (x + v * h * math.cos(mid), y + v * h * math.sin(mid), turned)
        if v and self._blocked(body, moved):
            if not body.touching:
                body.bumps += 1
            body.touching = True
            moved = (x, y, turned)
        elif v:
            body.touching = False
        body.moved(body.pose, moved)

    def obstacles(self) -> list[Segment]:
        """Every segment a body cannot cross: the map, built walls, blocks."""
        out = list(self.segments)
        for wall in self.walls.values():
            out += rectangle(*wall.at, math.radians(wall.heading), *wall.size)
        for block in self.blocks.values():
            out += block.segments()
        return out

    def _blocked(self, body: Body, moved: Pose) -> bool:
        """Whether ``body`` at ``moved`` overlaps something it was not overlapping more."""
        for seg in self.obstacles():
            d = distance_to_segment(moved[0], moved[1], seg)
            if d < body.radius and d < distance_to_segment(body.pose[0], body.pose[1], seg):
                return True
        for other in self.bodies.values():
            if other is body:
                continue
            reach = body.radius + other.radius
            d = math.hypot(moved[0] - other.pose[0], moved[1] - other.pose[1])
            if d < reach and d < math.hypot(
                body.pose[0] - other.pose[0], body.pose[1] - other.pose[1]
            ):
                return True
        return False

    def collides_block(self, block: BlockState, moved: Pose, pushers: list[Body]) -> bool:
        """Whether ``block`` at ``moved`` overlaps the map, a built wall, another
        block or a robot that is not pushing it (shapely's intersection tests)."""
        shape = Polygon([side[:2] for side in rectangle(*moved, *block.spec.size)])
        solids = [
            Polygon([s[:2] for s in rectangle(*w.at, math.radians(w.heading), *w.size)])
            for w in self.walls.values()
        ]
        solids += [
            Polygon([s[:2] for s in b.segments()]) for b in self.blocks.values() if b is not block
        ]
        if shape.intersects(self._walls) or any(shape.intersects(solid) for solid in solids):
            return True
        return any(
            shape.distance(Point(body.pose[0], body.pose[1])) < body.radius
            for body in self.bodies.values()
            if body not in pushers
        )

    def _bar(self) -> None:
        bar = self.scenario.world.bar
        if bar is None or self.bar_dropped is not None:
            return
        d = self.bar_length()
        if d is not None and abs(d - bar.length) > bar.tolerance:
            self.bar_dropped = (round(self.time, 3), d)

    def bar_length(self) -> float | None:
        bar = self.scenario.world.bar
        if bar is None:
            return None
        a, b = (self.bodies[n].pose for n in bar.robots)
        return math.hypot(a[0] - b[0], a[1] - b[1])

    def _sample(self) -> None:
        self.samples.append(
            Sample(
                round(self.time, 6),
                {n: b.pose for n, b in self.bodies.items()},
                {n: b.pose for n, b in self.blocks.items()},
                self.bar_length() if self.bar_dropped is None else None,
            )
        )

    # -- what sensors see --------------------------------------------------------

    def scene(self, *, exclude: str | None = None, robots: float | None = None) -> Scene:
        """What a ray can hit: walls, built walls and blocks, and robots as
        discs of radius ``robots`` (but ``exclude``; none when ``None``)."""
        index = {name: i for i, name in enumerate(self.labels)}
        segments: list[tuple[Segment, int]] = [(s, 0) for s in self.segments]
        for name, wall in self.walls.items():
            segments += [
                (s, index[name])
                for s in rectangle(*wall.at, math.radians(wall.heading), *wall.size)
            ]
        for name, block in self.blocks.items():
            segments += [(s, index[name]) for s in block.segments()]
        discs = []
        if robots is not None:
            discs = [
                (b.pose[0], b.pose[1], robots, index[n])
                for n, b in self.bodies.items()
                if n != exclude
            ]
        return Scene.build(segments, discs)

    def room_of(self, name: str) -> str | None:
        x, y, _ = self.bodies[name].pose
        return room_of(self.scenario.world.rooms, x, y)


def map_segments(scenario: Scenario) -> list[Segment]:
    """The walls of the rooms (each shared side once) with the doors cut out,
    and the obstacles."""
    sides: set[Segment] = set()
    for x0, y0, x1, y1 in scenario.world.rooms.values():
        for seg in ((x0, y0, x1, y0), (x1, y0, x1, y1), (x0, y1, x1, y1), (x0, y0, x0, y1)):
            sides.add(_ordered(seg))
    walls = sorted(sides)
    for door in scenario.world.doors.values():
        walls = [part for seg in walls for part in _cut(seg, door)]
    return walls + [_ordered(o) for o in scenario.world.obstacles]


def _ordered(seg: tuple[float, float, float, float]) -> Segment:
    a, b = (seg[0], seg[1]), (seg[2], seg[3])
    lo, hi = min(a, b), max(a, b)
    return (lo[0], lo[1], hi[0], hi[1])


def _cut(seg: Segment, door: Door) -> list[Segment]:
    """``seg`` without the door's opening, if the door is on it."""
    x1, y1, x2, y2 = seg
    length = math.hypot(x2 - x1, y2 - y1)
    if length == 0 or distance_to_segment(*door.at, seg) > 1e-6:
        return [seg]
    ux, uy = (x2 - x1) / length, (y2 - y1) / length
    centre = (door.at[0] - x1) * ux + (door.at[1] - y1) * uy
    lo, hi = centre - door.width / 2, centre + door.width / 2
    out: list[Segment] = []
    if lo > 1e-9:
        out.append((x1, y1, x1 + ux * lo, y1 + uy * lo))
    if hi < length - 1e-9:
        out.append((x1 + ux * hi, y1 + uy * hi, x2, y2))
    return out
