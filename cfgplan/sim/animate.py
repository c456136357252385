"""``animation.gif`` (``cfgplan simulate --animate``): the run, frame by frame.

One frame every :data:`FRAME` simulated seconds: the map, each robot where
it is with its trajectory so far, the blocks and the bar, and the running
configuration's cost. The map is drawn once; each frame adds the moving
parts, is captured, and takes them away again. Written with Pillow's GIF
encoder, which matplotlib already depends on: no system package is needed.
"""

from __future__ import annotations

from pathlib import Path

from matplotlib.artist import Artist
from PIL import Image

from cfgplan.sim.drawing import bounds, draw_block, draw_map, draw_robot, figure, shades
from cfgplan.sim.run import Run

__all__ = ["FRAME", "animate"]

FRAME = 0.5
"""Simulated seconds between two frames."""

DPI = 72
"""Resolution of the frames (dots per inch of a 4.5-inch wide figure)."""


def animate(run: Run, path: Path) -> None:
    world = run.world
    x0, y0, x1, y1 = bounds(world)
    colour = shades(list(world.bodies))
    radius = world.scenario.motion.radius
    every = max(1, round(FRAME / world.scenario.step))
    samples = world.samples
    fig = figure(4.5, 4.5 * (y1 - y0) / (x1 - x0) + 0.4)
    fig.set_dpi(DPI)
    ax = fig.add_subplot()
    draw_map(ax, world)
    fig.tight_layout()
    frames: list[Image.Image] = []
    for i in range(0, len(samples), every):
        sample = samples[i]
        before = set(ax.get_children())
        for name, block in world.blocks.items():
            draw_block(ax, sample.blocks[name], block.spec.size, final=True, label=name)
        if world.scenario.world.bar is not None:
            a, b = (sample.robots[n] for n in world.scenario.world.bar.robots)
            ax.plot([a[0], b[0]], [a[1], b[1]], color="#b5651d", lw=3, zorder=6)
        trail = samples[: i + 1 : every]
        for name in world.bodies:
            xs = [s.robots[name][0] for s in trail]
            ys = [s.robots[name][1] for s in trail]
            ax.plot(xs, ys, ls="none", marker="o", ms=1.8, color=colour[name], zorder=4)
            draw_robot(ax, sample.robots[name], radius, colour[name], filled=True, label=name)
        running = [s for s in run.recorder.segments if s.start <= sample.t]
        config = running[-1].config if running else None
        cost = "nothing runs" if config is None else f"cost {config.cost:g}"
        ax.set_title(f"{sample.t:5.1f} s   {cost}", fontsize=9, family="monospace")
        fig.canvas.draw()
        width, height = fig.canvas.get_width_height()
        rgba = bytes(fig.canvas.buffer_rgba())  # type: ignore[attr-defined]
        image = Image.frombytes("RGBA", (width, height), rgba)
        frames.append(image.convert("P", palette=Image.Palette.ADAPTIVE))
        for artist in set(ax.get_children()) - before:
            if isinstance(artist, Artist):
                artist.remove()
    if frames:
        frames[0].save(
            path, save_all=True, append_images=frames[1:], duration=int(FRAME * 500), loop=0
        )
