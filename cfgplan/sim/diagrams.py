"""The diagram of each configuration a run used (Figs. 4.3, 6.4, 6.8, 6.11,
6.12), drawn by the render backend (:mod:`cfgplan.backends.render`).

A configuration that ran twice (carry-a-bar going back to its laser) is
drawn once; files are numbered in the order the configurations first ran:
``configuration-1.png`` (cost 44), ``configuration-2.png``... — the numbers
the timeline's bars carry (:mod:`cfgplan.sim.timeline`). A simulation draws
its recorder's segments (:func:`draw_configurations`), ``cfgplan report`` a
trace's story (:func:`draw_story`); both through :func:`diagram_source`.
"""

from __future__ import annotations

import re
from pathlib import Path

from cfgplan.backends.dot import configuration_dot
from cfgplan.backends.render import render
from cfgplan.configuration.model import Configuration
from cfgplan.notation import call_text
from cfgplan.report.story import Story, cost_text
from cfgplan.sim.record import Segment

__all__ = ["diagram_source", "draw_configurations", "draw_story"]

_GOAL = re.compile(r"^[^()]+\((?P<args>.*)\)$")


def diagram_source(config: Configuration, number: int, goal: str, start: float) -> str:
    """The DOT source of configuration ``number``, titled with its goal, cost and start."""
    what = goal or f"configuration {number}"
    title = f"{what}: cost {cost_text(config)}, from {start:g} s"
    found = _GOAL.match(goal)
    first = [a.strip() for a in found.group("args").split(",")] if found else []
    return configuration_dot(config, title=title, first=first)


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
            source = diagram_source(seg.config, len(drawn) + 1, call_text(seg.goal), seg.start)
            (folder / name).write_bytes(render(source, "png"))
            drawn[key] = name
        out[index] = drawn[key]
    return out


def draw_story(story: Story, folder: Path) -> dict[int, str]:
    """Write ``configuration-N.png`` for each configuration of ``story``; its SVG, by number."""
    out: dict[int, str] = {}
    for number, span in sorted(story.configurations().items()):
        source = diagram_source(span.config, number, span.goal, span.start)
        (folder / f"configuration-{number}.png").write_bytes(render(source, "png"))
        out[number] = render(source, "svg").decode("utf-8")
    return out
