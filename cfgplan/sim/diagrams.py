"""The diagram of each configuration a simulation used (Figs. 4.3, 6.4, 6.8,
6.11, 6.12), drawn by the render backend (:mod:`cfgplan.backends.render`).

A configuration that ran twice (carry-a-bar going back to its laser) is
drawn once; files are numbered in the order the configurations first ran:
``configuration-1.png`` (cost 44), ``configuration-2.png``...
"""

from __future__ import annotations

from pathlib import Path

from cfgplan.backends.dot import configuration_dot
from cfgplan.backends.render import render
from cfgplan.configuration.cost import fmt
from cfgplan.notation import call_text
from cfgplan.sim.record import Segment

__all__ = ["draw_configurations"]


def draw_configurations(segments: list[Segment], folder: Path) -> dict[int, str]:
    """Write the diagrams; for each segment (by index) the file that shows it."""
    drawn: dict[object, str] = {}
    out: dict[int, str] = {}
    for index, seg in enumerate(segments):
        if seg.config is None:
            continue
        key = seg.config.identity()
        if key not in drawn:
            name = f"configuration-{len(drawn) + 1}.png"
            goal = call_text(seg.goal)
            title = f"{goal}: cost {fmt(seg.config.cost)}, from {seg.start:g} s"
            source = configuration_dot(seg.config, title=title, first=seg.goal[1:])
            (folder / name).write_bytes(render(source, "png"))
            drawn[key] = name
        out[index] = drawn[key]
    return out
