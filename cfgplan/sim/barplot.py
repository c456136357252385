"""``bar.png``: carry-a-bar's key measure, the bar's length over time (6.3).

The bar rests on both robots; it falls when they are further apart, or
closer, than its length plus or minus its tolerance (``summary.json``:
``bar.length``, ``bar.tolerance``). The picture is the distance between the
two robots at every step, the band it must stay in (shaded, its edges
dashed), each switch of configuration (a dotted line) and, when it fell,
the moment (a red cross).
"""

from __future__ import annotations

from pathlib import Path

from matplotlib.figure import Figure

from cfgplan.sim.drawing import Placer, figure, save
from cfgplan.sim.run import Run

__all__ = ["bar_figure", "draw_bar"]


def draw_bar(run: Run, path: Path) -> bool:
    """Write the picture when the scenario has a bar; whether it did."""
    fig = bar_figure(run)
    if fig is None:
        return False
    save(fig, path)
    return True


def bar_figure(run: Run) -> Figure | None:
    """The bar's length over time (module docstring); ``None`` without a bar."""
    world = run.world
    bar = world.scenario.world.bar
    if bar is None:
        return None
    points = [(s.t, s.bar) for s in world.samples if s.bar is not None]
    fig = figure(8.0, 3.2)
    ax = fig.add_axes((0.09, 0.16, 0.88, 0.72))
    low, high = bar.length - bar.tolerance, bar.length + bar.tolerance
    end = max(world.time, 1.0)
    ax.axhspan(
        low,
        high,
        color="#d5efcf",
        zorder=0,
        label=f"{bar.length:g} ± {bar.tolerance:g} m: the bar rests on both",
    )
    for edge in (low, high):
        ax.axhline(edge, color="#2e8b57", ls="--", lw=0.9)
    ax.plot(
        [t for t, _ in points],
        [d for _, d in points],
        color="#b5651d",
        lw=1.6,
        label=f"distance between {bar.robots[0]} and {bar.robots[1]}",
    )
    ax.axhline(bar.length, color="#777777", lw=0.6, ls=":")
    values = [d for _, d in points]
    span = max([high, *values]) - min([low, *values])
    ax.set_ylim(min([low, *values]) - 0.25 * span, max([high, *values]) + 0.45 * span)
    ax.set_xlim(0, end * 1.02)
    placer = Placer(fig)
    for n in run.recorder.of("switch", "no-configuration"):
        ax.axvline(n.t, color="#333333", ls=":", lw=0.9)
        was = n.record.get("from_cost")
        text = f" {'nothing' if was is None else was}→{n.record.get('to_cost', 'stop')}"
        placer.place(ax, text, [(n.t, ax.get_ylim()[1], {"va": "top"})], fontsize=7)
    if world.bar_dropped is not None:
        t, d = world.bar_dropped
        ax.plot([t], [d], ls="none", marker="X", ms=10, color="#d62728", label="the bar falls")
    ax.set_xlabel("simulated time (s)")
    ax.set_ylabel("bar length (m)")
    ax.legend(loc="lower right", fontsize=7, framealpha=0.95)
    title = run.loaded.scenario.title or run.loaded.scenario.name
    ax.set_title(f"{title}: the bar's length over time", fontsize=9, loc="left")
    ax.grid(color="#e5e5e5", lw=0.6)
    return fig
