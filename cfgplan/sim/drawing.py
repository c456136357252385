"""Drawing the world with matplotlib, headless (Agg), for every picture.

Figures are made with :class:`matplotlib.figure.Figure` and an Agg canvas,
never pyplot: no display, no global state, the same bytes for the same run
(PNG metadata without the software's version). Each robot has its own shade
everywhere (:func:`shades`): in the trajectories, the timeline and the
animation.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from matplotlib.artist import Artist
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.patches import Circle, Polygon, Rectangle
from matplotlib.text import Text
from matplotlib.transforms import Bbox

from cfgplan.sim.blocks import slot
from cfgplan.sim.geometry import Pose, rectangle
from cfgplan.sim.world import World

__all__ = ["SHADES", "Placer", "draw_map", "draw_robot", "figure", "save", "shades"]

SHADES = ("#8c8c8c", "#111111", "#1f5fa8", "#b5651d", "#2e8b57", "#7b3294")
"""Pippi gray and Emil black as in Fig. 6.6, then blue, brown, green, purple."""

CONFIG_COLOURS = ("#cfe1f2", "#fde0c5", "#d5efcf", "#e8d5f0", "#f6d0d0", "#fff3b0", "#d9d9d9")
"""Fill colours of the configurations in the timeline, in the order they ran."""


def shades(robots: list[str]) -> dict[str, str]:
    """Each robot's shade: Pippi and Emil as in the thesis, the others in turn."""
    fixed = {"Pippi": SHADES[0], "Emil": SHADES[1]}
    others = iter(SHADES[2:] * (1 + len(robots) // 4))
    return {r: fixed.get(r) or next(others) for r in robots}


def figure(width: float, height: float) -> Figure:
    fig = Figure(figsize=(width, height), dpi=110)
    FigureCanvasAgg(fig)
    return fig


def save(fig: Figure, path: Path) -> None:
    """The figure as PNG, or SVG when ``path`` ends in ``.svg`` (no date, fixed ids)."""
    if path.suffix == ".svg":
        import matplotlib

        with matplotlib.rc_context({"svg.hashsalt": "cfgplan", "svg.fonttype": "path"}):
            fig.savefig(path, format="svg", metadata={"Date": None, "Creator": None})
        return
    fig.savefig(path, format="png", metadata={"Software": None})


def bounds(world: World) -> tuple[float, float, float, float]:
    """The map's extent: every room, with a margin."""
    boxes = list(world.scenario.world.rooms.values())
    x0 = min(b[0] for b in boxes) - 0.3
    y0 = min(b[1] for b in boxes) - 0.3
    x1 = max(b[2] for b in boxes) + 0.3
    y1 = max(b[3] for b in boxes) + 0.3
    return x0, y0, x1, y1


def draw_map(ax: Axes, world: World) -> None:
    """Rooms, walls with their doors, disturbances, built walls, blocks' slots, marks."""
    s = world.scenario
    for name, (x0, y0, x1, y1) in s.world.rooms.items():
        ax.add_patch(
            Rectangle((x0, y0), x1 - x0, y1 - y0, facecolor="#f7f7f2", edgecolor="none", zorder=0)
        )
        ax.text(
            x0 + 0.12,
            y1 - 0.12,
            name,
            ha="left",
            va="top",
            fontsize=9,
            color="#666666",
            style="italic",
        )
    for x1, y1, x2, y2 in world.segments:
        ax.plot([x1, x2], [y1, y2], color="black", lw=3, solid_capstyle="butt", zorder=2)
    for name, door in world.doors.items():
        ax.annotate(
            name, door.at, xytext=(6, 6), textcoords="offset points", fontsize=8, color="#444444"
        )
    for m in s.world.magnetic:
        ax.add_patch(
            Circle(
                m.at,
                2 * m.radius,
                facecolor="#f4a582",
                edgecolor="#ca4a1f",
                alpha=0.35,
                lw=1,
                zorder=1,
            )
        )
        ax.annotate(
            f"magnetic\ndisturbance ({m.deflection:g}°)",
            m.at,
            xytext=(2.2 * m.radius * 72 / 2.54 / 10, 0),
            textcoords="offset points",
            fontsize=7,
            color="#ca4a1f",
            va="center",
        )
    for name, wall in world.walls.items():
        corners = rectangle(*wall.at, math.radians(wall.heading), *wall.size)
        ax.add_patch(
            Polygon(
                [c[:2] for c in corners],
                closed=True,
                facecolor="#9e9e9e",
                edgecolor="black",
                hatch="//",
                lw=1,
                zorder=2,
            )
        )
        ax.text(
            *wall.at,
            name,
            ha="center",
            va="center",
            fontsize=9,
            color="white",
            weight="bold",
            zorder=3,
        )
    for block in world.blocks.values():
        if block.spec.target is not None:
            target = slot(world.walls[block.spec.target], block.spec)
            corners = rectangle(*target, *block.spec.size)
            ax.add_patch(
                Polygon(
                    [c[:2] for c in corners],
                    closed=True,
                    fill=False,
                    edgecolor="#2e8b57",
                    ls=":",
                    lw=1.2,
                    zorder=1,
                )
            )
    for name, (x, y) in s.world.marks.items():
        ax.plot([x], [y], marker="P", color="#7b3294", ms=9, zorder=3)
        ax.annotate(
            name, (x, y), xytext=(6, -10), textcoords="offset points", fontsize=8, color="#7b3294"
        )
    x0, y0, x1, y1 = bounds(world)
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")


def draw_block(
    ax: Axes, pose: Pose, size: tuple[float, float], *, final: bool, label: str = ""
) -> None:
    corners = rectangle(*pose, *size)
    ax.add_patch(
        Polygon(
            [c[:2] for c in corners],
            closed=True,
            facecolor="#d9b38c" if final else "none",
            edgecolor="#7a4f1d",
            ls="-" if final else "--",
            lw=1.3,
            zorder=3,
        )
    )
    if label:
        ax.text(pose[0], pose[1], label, ha="center", va="center", fontsize=8, zorder=4)


def draw_robot(
    ax: Axes,
    pose: Pose,
    radius: float,
    colour: str,
    *,
    filled: bool,
    label: str = "",
    alpha: float = 0.85,
    zorder: float = 5,
) -> Circle:
    """A robot as in Fig. 6.2: a circle with a line giving its heading (the circle)."""
    x, y, h = pose
    disc = Circle(
        (x, y),
        radius,
        facecolor=colour if filled else "white",
        edgecolor=colour,
        alpha=alpha if filled else 1.0,
        lw=1.5,
        zorder=zorder,
    )
    ax.add_patch(disc)
    ax.plot(
        [x, x + radius * math.cos(h)],
        [y, y + radius * math.sin(h)],
        color="white" if filled else colour,
        lw=1.5,
        zorder=zorder + 1,
    )
    if label:
        ax.annotate(
            label,
            (x, y),
            xytext=(0, -14),
            textcoords="offset points",
            ha="center",
            va="top",
            fontsize=8,
            color=colour,
            zorder=6,
        )
    return disc


class Placer:
    """Labels that never overlap: each is put at the first of its candidate
    places where its extent, as the renderer measures it, meets no label
    already placed (nor leaves the figure)."""

    def __init__(self, fig: Figure, pad: float = 1.5) -> None:
        self.fig = fig
        self.renderer = fig.canvas.get_renderer()  # type: ignore[attr-defined]
        self.boxes: list[Bbox] = []
        self.pad = pad

    def _box(self, artist: Text) -> Bbox:
        return artist.get_window_extent(self.renderer).padded(self.pad)

    def free(self, box: Bbox) -> bool:
        inside = self.fig.bbox.padded(-1)
        whole = inside.x0 <= box.x0 and box.x1 <= inside.x1
        whole = whole and inside.y0 <= box.y0 and box.y1 <= inside.y1
        return whole and not any(box.overlaps(b) for b in self.boxes)

    def keep(self, artist: Artist) -> None:
        """Count something drawn elsewhere (a label, a disc) as taken."""
        self.boxes.append(artist.get_window_extent(self.renderer).padded(self.pad))

    def near(
        self,
        ax: Axes,
        text: str,
        xy: tuple[float, float],
        offsets: list[tuple[float, float]],
        **common: Any,
    ) -> Text | None:
        """``text`` next to the point ``xy``, at the first free offset (points):
        right of the point when the offset is positive, left when negative."""
        for dx, dy in offsets:
            ha = "left" if dx > 0 else "right" if dx < 0 else "center"
            va = "bottom" if dy > 0 else "top" if dy < 0 else "center"
            label = ax.annotate(
                text, xy, xytext=(dx, dy), textcoords="offset points", ha=ha, va=va, **common
            )
            box = self._box(label)
            if self.free(box):
                self.boxes.append(box)
                return label
            label.remove()
        return None

    def place(
        self,
        ax: Axes,
        text: str,
        candidates: list[tuple[float, float, dict[str, Any]]],
        *,
        within: float | None = None,
        **common: Any,
    ) -> Text | None:
        """``text`` at the first free candidate ``(x, y, options)``; ``None``
        (nothing drawn) when none is free, or none is narrower than ``within`` pixels."""
        for x, y, options in candidates:
            label = ax.text(x, y, text, **common, **options)
            box = self._box(label)
            if (within is None or box.width <= within) and self.free(box):
                self.boxes.append(box)
                return label
            label.remove()
        return None
