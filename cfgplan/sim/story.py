"""A simulation's :class:`~cfgplan.report.story.Story`: what its timeline and
diagrams draw, the same pictures ``cfgplan report`` draws from a trace.

The moments (switches, failures, recoveries) come from the recorder's
events through :func:`cfgplan.report.story.from_records`, as for a trace;
the configurations are the recorder's segments themselves (the planner's
configurations, with their costs), numbered in the order they first ran,
like the ``configuration-N.png`` files (:mod:`cfgplan.sim.diagrams`).
"""

from __future__ import annotations

from typing import Any

from cfgplan.notation import call_text
from cfgplan.report.story import Span, Story, from_records
from cfgplan.sim.run import Run

__all__ = ["story_of"]


def story_of(run: Run) -> Story:
    """The story of a finished simulation (module docstring)."""
    world = run.world
    summary: dict[str, Any] = {
        "title": run.loaded.scenario.title or run.loaded.scenario.name,
        "steps": [st.summary() for st in run.steps],
        "world_changes": [{"time": t, "what": w} for t, w in world.changes],
    }
    if world.bar_dropped is not None:
        summary["bar"] = {"dropped": True, "dropped_at": world.bar_dropped[0]}
    records = [n.record for n in run.recorder.notable]
    story = from_records(records, summary, origin=0.0)
    story.robots = list(world.bodies)
    story.end = max(world.time, story.end)
    story.spans = []
    numbers: dict[object, int] = {}
    for seg in run.recorder.segments:
        if seg.config is None:
            continue
        number = numbers.setdefault(seg.config.identity(), len(numbers) + 1)
        end = seg.end if seg.end is not None else world.time
        story.spans.append(Span(number, seg.config, seg.start, end, call_text(seg.goal)))
    return story
