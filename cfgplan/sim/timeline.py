"""``timeline.png``: which configuration ran when, on which robots, as Fig. 6.5.

Fig. 6.5 summarises the cross-a-door experiment as a schema: Pippi's
configuration, Emil's, the reconfiguration, the manual interventions. Here
time runs left to right; the top row holds the steps (goals); below, one row
per robot, a bar for every configuration it took part in, coloured and
numbered like the ``configuration-N`` diagrams (``#2 · 47 · cross-door``: the
number, the cost, what the robot did in it, as much as fits; the key under
the picture says the rest). A dashed line marks each switch, its label
(``44 → 47: compass(Emil) failed``) above the steps; a red cross marks a
failure and a green ring the recovery, both on the row of the robot whose
resource it is; a purple triangle a world change.

The picture draws a :class:`~cfgplan.report.story.Story`: a simulation's
(:mod:`cfgplan.sim.story`) or a trace's (``cfgplan report``). Every label is
placed where the renderer measures that it meets no other
(:class:`~cfgplan.sim.drawing.Placer`).
"""

from __future__ import annotations

import textwrap
from pathlib import Path
from typing import Any

from matplotlib.figure import Figure

from cfgplan.report.story import Story, cost_text, role
from cfgplan.sim.drawing import CONFIG_COLOURS, Placer, figure, save, shades

__all__ = ["draw_timeline", "timeline_figure"]

WIDTH = 10.0
"""Inches."""
ROW = 0.55
"""Inches per row."""
LEVEL = 0.34
"""Rows between two levels of switch labels."""


def draw_timeline(story: Story, path: Path) -> None:
    save(timeline_figure(story), path)


def _key(story: Story) -> list[str]:
    """A line per configuration: its number, cost and what each robot did in it."""
    out = []
    for number, span in sorted(story.configurations().items()):
        roles = "; ".join(f"{r}: {role(span.config, r)}" for r in span.config.agents)
        line = f"#{number}  cost {cost_text(span.config)}"
        line += f" ({span.goal})" if span.goal else ""
        out.append(textwrap.shorten(f"{line} — {roles}", 150))
    return out


def timeline_figure(story: Story) -> Figure:
    """The timeline of ``story`` (module docstring)."""
    robots = list(story.robots)
    colour = shades(robots)
    end = max(story.end, 1.0)
    rows = {name: len(robots) - i for i, name in enumerate(robots)}
    top = len(robots) + 1
    key = _key(story)
    switches = story.of("switch", "no-configuration")
    # the frame first, so that every label is measured where it will be
    fig = figure(WIDTH, 1.0)
    left, right = 1.05, 0.25
    ax = fig.add_axes((0, 0, 1, 1))
    ax.set_xlim(0, end * 1.02)
    width_px = (WIDTH - left - right) * fig.dpi
    levels = _levels(fig, story, end, width_px)
    units = top + 1.0 + LEVEL * (max((lv for lv, _ in levels.values()), default=-1) + 1) + 0.2
    below = 0.55 + 0.16 * len(key)
    height = units * ROW + below + 0.35
    fig.set_size_inches(WIDTH, height)
    ax.set_position(
        (left / WIDTH, below / height, 1 - (left + right) / WIDTH, units * ROW / height)
    )
    ax.set_ylim(0, units)
    placer = Placer(fig)
    # the steps
    for i, step in enumerate(story.steps, 1):
        if step.started is None:
            continue
        stop = step.achieved if step.achieved is not None else end
        ax.barh(
            top,
            stop - step.started,
            left=step.started,
            height=0.5,
            color="#eeeeee",
            edgecolor="#777777",
        )
        mark = " ✓" if step.achieved is not None else " (not accomplished)"
        span_px = (stop - step.started) / (end * 1.02) * width_px
        for text in (f"step {i}: {step.goal}{mark}", f"step {i}{mark}", f"{i}"):
            if placer.place(
                ax,
                text,
                [(step.started + 0.004 * end, top, {})],
                within=span_px - 4,
                va="center",
                fontsize=8,
            ):
                break
    # the configurations, robot by robot
    for span in story.spans:
        fill = CONFIG_COLOURS[(span.number - 1) % len(CONFIG_COLOURS)]
        span_px = (span.end - span.start) / (end * 1.02) * width_px
        for robot in span.config.agents:
            if robot not in rows:
                continue
            ax.barh(
                rows[robot],
                span.end - span.start,
                left=span.start,
                height=0.55,
                color=fill,
                edgecolor="#555555",
                lw=0.8,
            )
            cost = cost_text(span.config)
            texts = [
                f"#{span.number} · {cost} · {role(span.config, robot)}",
                f"#{span.number} · {cost}",
                f"#{span.number}",
            ]
            at: list[tuple[float, float, dict[str, Any]]] = [
                (span.start + 0.003 * end, rows[robot], {})
            ]
            if not any(
                placer.place(ax, t, at, within=span_px - 3, va="center", fontsize=7) for t in texts
            ):
                middle = (span.start + span.end) / 2
                placer.place(
                    ax,
                    f"#{span.number}",
                    [(middle, rows[robot] + 0.3, {})],
                    ha="center",
                    va="bottom",
                    fontsize=7,
                )
    # switches: a line below the steps and one above them, up to the label
    for n in switches:
        level, right = levels[id(n)]
        y = top + 0.5 + LEVEL * level
        ax.vlines(n.t, 0, top - 0.25, color="#333333", ls="--", lw=0.9, zorder=1)
        ax.vlines(n.t, top + 0.25, y + 0.05, color="#333333", ls="--", lw=0.9, zorder=1)
        text = _switch_text(n.text) + " " if right else " " + _switch_text(n.text)
        label = ax.text(n.t, y, text, fontsize=7, ha="right" if right else "left", va="bottom")
        placer.keep(label)
    # failures and recoveries, on the row of the robot whose resource it is
    for n in story.of("failure", "recovery"):
        if n.robot not in rows:
            continue
        y = rows[n.robot]
        failed = n.what == "failure"
        tint = "#d62728" if failed else "#2e8b57"
        if failed:
            ax.plot(
                [n.t], [y + 0.3], ls="none", marker="X", ms=9, color=tint, mec="white", zorder=5
            )
        else:
            ax.plot(
                [n.t],
                [y + 0.3],
                ls="none",
                marker="o",
                ms=8,
                mfc="white",
                mec=tint,
                mew=1.8,
                zorder=5,
            )
        placer.place(
            ax,
            n.text,
            [
                (n.t + 0.006 * end, y + 0.32, {"va": "bottom"}),
                (n.t - 0.006 * end, y + 0.32, {"va": "bottom", "ha": "right"}),
                (n.t + 0.006 * end, y - 0.3, {"va": "top"}),
                (n.t - 0.006 * end, y - 0.3, {"va": "top", "ha": "right"}),
            ],
            fontsize=7,
            color=tint,
            zorder=6,
        )
    for n in story.of("change", "drop"):
        tint = "#7b3294" if n.what == "change" else "#d62728"
        if n.what == "drop":
            ax.vlines(n.t, 0, top - 0.25, color=tint, lw=1.5)
        ax.plot(
            [n.t], [0.35], ls="none", marker="^" if n.what == "change" else "v", ms=8, color=tint
        )
        placer.place(
            ax,
            n.text,
            [
                (n.t + 0.008 * end, 0.35, {"va": "center"}),
                (n.t - 0.008 * end, 0.35, {"va": "center", "ha": "right"}),
                (n.t + 0.008 * end, 0.12, {"va": "center"}),
            ],
            fontsize=7,
            color=tint,
        )
    ax.set_yticks([top, *rows.values()], ["steps", *rows])
    for tick, name in zip(ax.get_yticklabels()[1:], rows, strict=True):
        tick.set_color(colour[name])
        tick.set_fontweight("bold")
    ax.set_xlabel(story.clock)
    title = (
        f"{story.title}: configurations over time" if story.title else "configurations over time"
    )
    ax.set_title(title, fontsize=9, loc="left")
    ax.grid(axis="x", color="#dddddd", lw=0.6)
    ax.set_axisbelow(True)
    for i, line in enumerate(key):
        fig.text(
            left / WIDTH,
            (0.1 + 0.16 * (len(key) - 1 - i)) / height,
            line,
            fontsize=7,
            color="#333333",
        )
    return fig


def _switch_text(text: str) -> str:
    return textwrap.shorten(text, 60, placeholder="…")


def _levels(fig: Figure, story: Story, end: float, width_px: float) -> dict[int, tuple[int, bool]]:
    """The level of each switch's label: the lowest where it meets no earlier label."""
    renderer = fig.canvas.get_renderer()  # type: ignore[attr-defined]
    fig.set_size_inches(WIDTH, 2.0)
    taken: list[list[tuple[float, float]]] = []
    out: dict[int, tuple[int, bool]] = {}
    for n in story.of("switch", "no-configuration"):
        probe = fig.text(0, 0, " " + _switch_text(n.text), fontsize=7)
        wide = probe.get_window_extent(renderer).width + 6
        probe.remove()
        x0 = n.t / (end * 1.02) * width_px
        right = x0 + wide > width_px  # near the end: the label to the left of its line
        span = (x0 - wide, x0 + 3) if right else (x0 - 3, x0 + wide)
        level = 0
        while level < len(taken) and any(a < span[1] and span[0] < b for a, b in taken[level]):
            level += 1
        if level == len(taken):
            taken.append([])
        taken[level].append(span)
        out[id(n)] = (level, right)
    return out
