"""``timeline.png``: which configuration ran when, on which robots, as Fig. 6.5.

Fig. 6.5 summarises the cross-a-door experiment as a schema: Pippi's
configuration, Emil's, the reconfiguration, the manual interventions. Here
time runs left to right; the top row holds the steps (goals) of the
scenario; below, one row per robot, a bar for every configuration it took
part in, coloured by configuration and labelled with its cost and what the
robot did in it (its action, or ``helps``). A dashed line and its label
mark each switch (``44 → 47`` and why), a red cross a failure on the robot
that saw it, a purple triangle a world change, a green ring a resource back.
"""

from __future__ import annotations

import textwrap
from pathlib import Path

from cfgplan.configuration.model import Configuration
from cfgplan.sim.drawing import CONFIG_COLOURS, figure, save, shades
from cfgplan.sim.run import Run

__all__ = ["draw_timeline"]


def _role(config: Configuration, robot: str) -> str:
    """What ``robot`` does in ``config``: its action, else how many functionalities it runs."""
    mine = [f for f in config.functionalities if f.robot == robot]
    sinks = [f for f in mine if not any(c.source == f.label for c in config.channels)]
    if sinks:
        return ", ".join(f.name for f in sinks)
    return f"helps ({len(mine)} functionalities)"


def draw_timeline(run: Run, path: Path) -> None:
    world = run.world
    rec = run.recorder
    robots = list(world.bodies)
    colour = shades(robots)
    end = max(world.time, 1.0)
    fig = figure(10.0, 1.6 + 0.75 * (len(robots) + 1))
    ax = fig.add_subplot()
    rows = {name: len(robots) - i for i, name in enumerate(robots)}
    top = len(robots) + 1
    # the steps
    for i, step in enumerate(run.steps, 1):
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
        ax.text(
            step.started + 0.01 * end,
            top,
            f"step {i}: {step.goal}{mark}",
            va="center",
            fontsize=8,
            clip_on=True,
        )
    # the configurations, robot by robot
    seen: dict[tuple[object, ...], int] = {}
    for seg in rec.segments:
        if seg.config is None:
            continue
        key = seg.config.identity()
        index = seen.setdefault(key, len(seen))
        fill = CONFIG_COLOURS[index % len(CONFIG_COLOURS)]
        stop = seg.end if seg.end is not None else end
        for robot in seg.config.agents:
            if robot not in rows:
                continue
            bars = ax.barh(
                rows[robot],
                stop - seg.start,
                left=seg.start,
                height=0.55,
                color=fill,
                edgecolor="#555555",
                lw=0.8,
            )
            label = f"{seg.config.cost:g}: {_role(seg.config, robot)}"
            inside = ax.text(seg.start + 0.005 * end, rows[robot], label, va="center", fontsize=7)
            inside.set_clip_path(bars.patches[0])  # a short bar shows what fits
            inside.set_clip_on(True)
    # switches, failures, recoveries, world changes
    last = -end
    level = 0
    for n in rec.of("switch", "no-configuration"):
        ax.axvline(n.t, color="#333333", ls="--", lw=0.9)
        cause = str(n.record.get("cause", ""))
        was = n.record.get("from_cost")
        to = n.record.get("to_cost", "stop")
        text = f"{'nothing' if was is None else was} → {to}: " + textwrap.shorten(cause, 40)
        # labels close in time go one above the other
        level = level + 1 if n.t - last < 0.25 * end else 0
        last = n.t
        ax.text(
            n.t,
            top + 0.4 + 0.28 * level,
            " " + text,
            fontsize=7,
            ha="left",
            va="bottom",
            bbox={"boxstyle": "round,pad=0.15", "fc": "white", "ec": "none", "alpha": 0.85},
        )
    for n in rec.of("failure"):
        who = str(n.record.get("resource", ""))  # a robot lost, on its own row
        who = who if who in rows else str(n.record.get("detected_by", ""))
        if who in rows:
            ax.plot(
                [n.t], [rows[who] + 0.3], marker="X", ms=10, color="#d62728", mec="white", zorder=5
            )
            ax.text(
                n.t,
                rows[who] + 0.33,
                f" {n.record.get('resource')} fails",
                fontsize=7,
                color="#d62728",
                va="bottom",
            )
    for n in rec.of("recovery"):
        who = str(n.record.get("detected_by", ""))
        if who in rows:
            ax.plot([n.t], [rows[who] - 0.3], marker="o", ms=8, mfc="none", mec="#2e8b57", mew=1.5)
            ax.text(
                n.t,
                rows[who] - 0.33,
                f" {n.record.get('resource')} works again",
                fontsize=7,
                color="#2e8b57",
                va="top",
            )
    for t, what in world.changes:
        ax.plot([t], [0.35], marker="^", ms=9, color="#7b3294")
        ax.text(t, 0.35, f" {what}", fontsize=7, color="#7b3294", va="center")
    if world.bar_dropped is not None:
        t, d = world.bar_dropped
        ax.axvline(t, color="#d62728", lw=1.5)
        ax.text(t, 0.35, f" the bar falls ({d:.2f} m)", fontsize=8, color="#d62728", va="center")
    ax.set_yticks([top, *rows.values()], ["steps", *rows])
    for tick, name in zip(ax.get_yticklabels()[1:], rows, strict=True):
        tick.set_color(colour[name])
        tick.set_fontweight("bold")
    ax.set_ylim(0, top + 1.2 + 0.28 * max(0, len(rec.of("switch", "no-configuration")) - 1))
    ax.set_xlim(0, end * 1.02)
    ax.set_xlabel("simulated time (s)")
    title = run.loaded.scenario.title or run.loaded.scenario.name
    ax.set_title(f"{title}: configurations over time", fontsize=9, loc="left")
    ax.grid(axis="x", color="#dddddd", lw=0.6)
    ax.set_axisbelow(True)
    fig.tight_layout()
    save(fig, path)
