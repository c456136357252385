"""``trajectories.png``: the map and where every robot went, as Fig. 6.6.

Fig. 6.6 shows the two rooms, Pippi's trajectory as gray dots and Emil's as
black dots, with Pippi standing at her observing position and Emil having
just accomplished his task. Here each robot's trajectory is dots in its own
shade (one every half second), drawn over its start pose (a hollow circle)
and its end pose (a light filled one), each with a line giving its heading
(Fig. 6.2). A star marks each switch of configuration (``44→47``) on the
robot it concerns (whose resource failed or recovered, or whose step comes
next), a red cross a resource failing, a green ring a step accomplished.
Blocks are drawn where they started (dashed) and ended, with the slot they
should fill (dotted); the bar at a few moments and where it ended. When a
laser's functionality fails (build-a-wall), the laser's view at that moment
(:mod:`cfgplan.sim.laserview`): what the block hid from it.

The legend sits under the map, never on it; every label is placed where the
renderer measures that it meets no other label, disc or marker
(:class:`~cfgplan.sim.drawing.Placer`).
"""

from __future__ import annotations

from pathlib import Path

from matplotlib.axes import Axes
from matplotlib.figure import Figure

from cfgplan.sim.drawing import (
    Placer,
    bounds,
    draw_block,
    draw_map,
    draw_robot,
    figure,
    save,
    shades,
)
from cfgplan.sim.laserview import draw_laser_view, laser_failures
from cfgplan.sim.run import Run
from cfgplan.sim.world import Sample

__all__ = ["draw_trajectories", "trajectories_figure"]

DOT_EVERY = 0.5
"""Seconds between two dots of a trajectory."""

_AROUND = [(9, 7), (9, -7), (-9, 7), (-9, -7), (0, 14), (0, -14), (16, 0), (-16, 0)]
_AROUND += [(22, 18), (-22, 18), (22, -18), (-22, -18), (30, 0), (-30, 0)]
"""Where a label may go around its point, in points, nearest first."""


def _at(samples: list[Sample], t: float) -> Sample:
    """The sample nearest to time ``t``."""
    return min(samples, key=lambda s: abs(s.t - t))


def draw_trajectories(run: Run, path: Path) -> None:
    save(trajectories_figure(run), path)


def trajectories_figure(run: Run) -> Figure:
    """The trajectories of ``run`` (module docstring)."""
    world = run.world
    x0, y0, x1, y1 = bounds(world)
    width, left, right, top, bottom = 7.0, 0.7, 0.2, 0.55, 1.15
    inner = width - left - right
    height = inner * (y1 - y0) / (x1 - x0) + top + bottom
    fig = figure(width, height)
    ax = fig.add_axes((left / width, bottom / height, inner / width, 1 - (top + bottom) / height))
    draw_map(ax, world)
    placer = Placer(fig)
    samples = world.samples
    names = list(world.bodies)
    colour = shades(names)
    radius = world.scenario.motion.radius
    every = max(1, round(DOT_EVERY / world.scenario.step))
    failures = [(n.t, str(n.record.get("resource", ""))) for n in run.recorder.of("failure")]
    hidden: list[tuple[str, tuple[float, float]]] = []
    for t, robot in laser_failures(world, failures):
        points, said = draw_laser_view(ax, world, _at(samples, t), robot)
        if points:
            ax.plot(
                [],
                [],
                ls="none",
                marker="s",
                ms=4,
                color="#d62728",
                label=f"what a block hid from {robot}'s laser ({t:g} s)",
            )
            middle = (
                sum(p[0] for p in points) / len(points),
                sum(p[1] for p in points) / len(points),
            )
            hidden.append((f"{said} from {robot}'s laser ({t:g} s)", middle))
    if world.scenario.world.bar is not None:
        a, b = world.scenario.world.bar.robots
        for sample in samples[:: every * 6]:
            (ax_, ay_, _), (bx, by, _) = sample.robots[a], sample.robots[b]
            ax.plot([ax_, bx], [ay_, by], color="#b5651d", lw=1, alpha=0.35, zorder=3)
        last = samples[-1]
        ax.plot(
            [last.robots[a][0], last.robots[b][0]],
            [last.robots[a][1], last.robots[b][1]],
            color="#b5651d",
            lw=3,
            zorder=6,
            label="the bar",
        )
    for name, block in world.blocks.items():
        draw_block(ax, samples[0].blocks[name], block.spec.size, final=False)
        draw_block(ax, block.pose, block.spec.size, final=True, label=name)
    discs = []
    for name in names:
        discs.append(draw_robot(ax, samples[0].robots[name], radius, colour[name], filled=False))
        discs.append(
            draw_robot(
                ax, world.bodies[name].pose, radius, colour[name], filled=True, alpha=0.4, zorder=3
            )
        )
    for name in names:
        xs = [s.robots[name][0] for s in samples[::every]]
        ys = [s.robots[name][1] for s in samples[::every]]
        moved = world.bodies[name].travelled > 0.05
        ax.plot(
            xs,
            ys,
            ls="none",
            marker="o",
            ms=2.6,
            color=colour[name],
            zorder=7,
            label=f"{name}" + ("" if moved else " (stands still)"),
        )
    for drawn in [*discs, *ax.texts, *(p for p in ax.patches if p.get_zorder() >= 2)]:
        placer.keep(drawn)
    _moments(ax, run, samples, placer)
    box = {"boxstyle": "round,pad=0.15", "fc": "white", "alpha": 0.8, "lw": 0}
    for name in names:
        placer.near(
            ax,
            name,
            world.bodies[name].pose[:2],
            [(dx * 1.6, dy * 1.6) for dx, dy in _AROUND],
            fontsize=9,
            color=colour[name],
            weight="bold",
            zorder=9,
            bbox=box,
        )
    for text, xy in hidden:
        placer.near(
            ax,
            text,
            xy,
            [(dx * 2, dy * 2) for dx, dy in _AROUND],
            fontsize=7,
            color="#d62728",
            zorder=12,
            bbox=box,
        )
    title = run.loaded.scenario.title or run.loaded.scenario.name
    ok = "accomplished" if not _failed(run) else "not accomplished"
    ax.set_title(f"{title}\n{ok}, {world.time:g} s (seed {world.seed})", fontsize=9)
    handles, labels = ax.get_legend_handles_labels()
    fig.legend(
        handles,
        labels,
        loc="lower center",
        ncol=3,
        fontsize=7,
        frameon=False,
        bbox_to_anchor=(0.5, 0.0),
    )
    return fig


def _failed(run: Run) -> bool:
    from cfgplan.sim.report import why

    return bool(why(run))


def _moments(ax: Axes, run: Run, samples: list[Sample], placer: Placer) -> None:
    """Switches, failures and accomplished steps, on the paths; markers first, then labels."""
    rec = run.recorder
    labels: list[tuple[str, tuple[float, float], dict[str, object]]] = []
    star = "switch of configuration"
    for n in rec.of("switch"):
        cause = str(n.record.get("cause", ""))
        who = _owner(cause, run)
        sample = _at(samples, n.t)
        if who not in sample.robots:
            continue
        x, y, _ = sample.robots[who]
        placer.keep(
            ax.plot(
                [x],
                [y],
                ls="none",
                marker="*",
                ms=18,
                color="#f2b701",
                mec="black",
                zorder=10,
                label=star,
            )[0]
        )
        star = "_"
        was = n.record.get("from_cost")
        text = f"{'nothing' if was is None else was}→{n.record['to_cost']} ({n.t:g} s)"
        if cause.startswith("next step"):
            text = f"next step: {n.record['to_cost']} ({n.t:g} s)"
        labels.append((text, (x, y), {"fontsize": 8, "weight": "bold"}))
    cross = "a resource fails"
    for n in rec.of("failure"):
        resource = str(n.record.get("resource", ""))
        who = _owner(resource, run) or str(n.record.get("detected_by", ""))
        sample = _at(samples, n.t)
        if who not in sample.robots:
            continue
        x, y, _ = sample.robots[who]
        placer.keep(
            ax.plot(
                [x],
                [y],
                ls="none",
                marker="X",
                ms=9,
                color="#d62728",
                mec="white",
                zorder=11,
                label=cross,
            )[0]
        )
        cross = "_"
        labels.append((f"{resource} fails", (x, y), {"fontsize": 7, "color": "#d62728"}))
    ring = "step accomplished"
    for i, step in enumerate(run.steps, 1):
        if step.achieved is None:
            continue
        sample = _at(samples, step.achieved)
        who = _owner(step.goal, run)
        if who not in sample.robots:
            continue
        x, y, _ = sample.robots[who]
        placer.keep(
            ax.plot(
                [x],
                [y],
                ls="none",
                marker="o",
                ms=16,
                mfc="none",
                mec="#2e8b57",
                mew=2,
                zorder=9,
                label=ring,
            )[0]
        )
        ring = "_"
        if len(run.steps) > 1:
            labels.append((f"step {i}", (x, y), {"fontsize": 7, "color": "#2e8b57"}))
    box = {"boxstyle": "round,pad=0.15", "fc": "white", "alpha": 0.85, "lw": 0}
    for text, xy, options in labels:
        placer.near(ax, text, xy, _AROUND, zorder=12, bbox=box, **options)  # type: ignore[arg-type]


def _owner(text: str, run: Run) -> str:
    """The first robot named in ``text`` (a goal, a resource, or a switch's cause)."""
    words = text.replace("(", " ").replace(")", " ").replace(",", " ").split()
    for w in words:
        if w in run.world.bodies:
            return w
    goal = run.steps[0].goal.replace("(", " ").replace(")", " ").replace(",", " ").split()
    return next((w for w in goal if w in run.world.bodies), "")
