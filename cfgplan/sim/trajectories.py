"""``trajectories.png``: the map and where every robot went, as Fig. 6.6.

Fig. 6.6 shows the two rooms, Pippi's trajectory as gray dots and Emil's as
black dots, with Pippi standing at her observing position and Emil having
just accomplished his task. Here each robot's trajectory is dots in its own
shade (one every half second), its start pose a hollow circle and its end
pose a filled one, each with a line giving its heading (Fig. 6.2); a star
on each path marks a switch of configuration (``44→47``), a red cross a
resource failing, a green ring a step accomplished. Blocks are drawn where
they started (dashed) and ended, with the slot they should fill (dotted);
the bar at a few moments and where it ended.
"""

from __future__ import annotations

from pathlib import Path

from matplotlib.axes import Axes

from cfgplan.sim.drawing import bounds, draw_block, draw_map, draw_robot, figure, save, shades
from cfgplan.sim.run import Run
from cfgplan.sim.world import Sample

__all__ = ["draw_trajectories"]

DOT_EVERY = 0.5
"""Seconds between two dots of a trajectory."""


def _at(samples: list[Sample], t: float) -> Sample:
    """The sample nearest to time ``t``."""
    best = min(samples, key=lambda s: abs(s.t - t))
    return best


def draw_trajectories(run: Run, path: Path) -> None:
    world = run.world
    x0, y0, x1, y1 = bounds(world)
    width = 7.0
    fig = figure(width, width * (y1 - y0) / (x1 - x0) + 0.8)
    ax = fig.add_subplot()
    draw_map(ax, world)
    samples = world.samples
    names = list(world.bodies)
    colour = shades(names)
    radius = world.scenario.motion.radius
    every = max(1, round(DOT_EVERY / world.scenario.step))
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
            zorder=4,
            label=f"{name}" + ("" if moved else " (stands still)"),
        )
        draw_robot(ax, samples[0].robots[name], radius, colour[name], filled=False)
        draw_robot(ax, world.bodies[name].pose, radius, colour[name], filled=True)
        end = world.bodies[name].pose
        off = 0.75 * radius * 72 * width * 0.8 / (x1 - x0) + 2  # the disc's radius in points
        ax.annotate(
            name,
            end[:2],
            xytext=(-off, -off),
            textcoords="offset points",
            fontsize=9,
            ha="right",
            va="top",
            color=colour[name],
            weight="bold",
            zorder=7,
        )
    _moments(ax, run, samples)
    title = run.loaded.scenario.title or run.loaded.scenario.name
    ok = "accomplished" if not _failed(run) else "not accomplished"
    ax.set_title(f"{title}\n{ok}, {world.time:g} s (seed {world.seed})", fontsize=9)
    ax.legend(loc="lower right", fontsize=7, framealpha=0.9)
    fig.tight_layout()
    save(fig, path)


def _failed(run: Run) -> bool:
    from cfgplan.sim.report import why

    return bool(why(run))


def _moments(ax: Axes, run: Run, samples: list[Sample]) -> None:
    """Switches, failures and accomplished steps, on the paths."""
    rec = run.recorder
    star_label = "switch of configuration"
    for n in rec.of("switch"):
        sample = _at(samples, n.t)
        cause = str(n.record.get("cause", ""))
        owner = _owner(cause, run)
        text = f"{n.record['from_cost']}→{n.record['to_cost']} ({n.t:g} s)"
        if cause.startswith("next step"):
            text = f"next step: {n.record['to_cost']} ({n.t:g} s)"
        for name, (x, y, _) in sample.robots.items():
            ax.plot(
                [x],
                [y],
                marker="*",
                ms=13,
                color="#f2b701",
                markeredgecolor="black",
                zorder=8,
                label=star_label,
            )
            star_label = "_"
            if name == owner:
                ax.annotate(
                    text,
                    (x, y),
                    xytext=(8, -14),
                    textcoords="offset points",
                    fontsize=8,
                    weight="bold",
                    zorder=9,
                    bbox={"boxstyle": "round,pad=0.2", "fc": "white", "alpha": 0.8, "lw": 0},
                )
    cross_label = "a resource fails"
    for n in rec.of("failure"):
        who = str(n.record.get("detected_by", ""))
        sample = _at(samples, n.t)
        if who in sample.robots:
            x, y, _ = sample.robots[who]
            ax.plot(
                [x],
                [y],
                marker="X",
                ms=11,
                color="#d62728",
                markeredgecolor="white",
                zorder=9,
                label=cross_label,
            )
            cross_label = "_"
            left = x < sum(ax.get_xlim()) / 2  # the label towards the middle of the map
            ax.annotate(
                f"{n.record.get('resource')} fails",
                (x, y),
                xytext=(10 if left else -10, 10),
                textcoords="offset points",
                ha="left" if left else "right",
                fontsize=7,
                color="#d62728",
                zorder=9,
            )
    ring_label = "step accomplished"
    for i, step in enumerate(run.steps, 1):
        if step.achieved is None:
            continue
        sample = _at(samples, step.achieved)
        owner = _owner(step.goal, run)
        if owner in sample.robots:
            x, y, _ = sample.robots[owner]
            ax.plot(
                [x],
                [y],
                marker="o",
                ms=16,
                mfc="none",
                mec="#2e8b57",
                mew=2,
                zorder=9,
                label=ring_label,
            )
            ring_label = "_"
            if len(run.steps) > 1:
                ax.annotate(
                    f"step {i}",
                    (x, y),
                    xytext=(10, 6),
                    textcoords="offset points",
                    fontsize=7,
                    color="#2e8b57",
                    zorder=9,
                )


def _owner(text: str, run: Run) -> str:
    """The first robot named in ``text`` (a goal, or a switch's cause)."""
    words = text.replace("(", " ").replace(")", " ").replace(",", " ").split()
    for w in words:
        if w in run.world.bodies:
            return w
    goal = run.steps[0].goal.replace("(", " ").replace(")", " ").replace(",", " ").split()
    return next((w for w in goal if w in run.world.bodies), "")
