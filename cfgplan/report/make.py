"""The whole report of a run, picture by picture (``cfgplan report RUN [-o DIR]``).

DIR receives ``timeline.png`` and ``configuration-N.png`` for every run;
``trajectories.png`` (and ``bar.png`` with a bar) when the run is a
simulation that :mod:`cfgplan.report.replay` could run again; and
``report.html``, all of it in one self-contained page. The pictures are
drawn by the simulator's drawing modules, the ones ``cfgplan simulate``
uses (:mod:`cfgplan.sim.timeline`, :mod:`cfgplan.sim.diagrams`,
:mod:`cfgplan.sim.trajectories`, :mod:`cfgplan.sim.barplot`).
"""

from __future__ import annotations

import io
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

from matplotlib.figure import Figure as MplFigure

from cfgplan.report.page import Figure, page
from cfgplan.report.replay import replay
from cfgplan.report.source import Source, read_run
from cfgplan.report.story import Story, from_records

__all__ = ["Made", "ReportOptions", "make_report", "report_files"]


@dataclass(frozen=True)
class ReportOptions:
    """``replay``: run a simulation again for its poses (:mod:`cfgplan.report.replay`)."""

    replay: bool = True


@dataclass
class Made:
    """What was written (file names, in order), and what the report could not draw."""

    files: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    story: Story | None = None


def report_files(folder: Path) -> list[str]:
    """The files of an earlier report in ``folder`` (written over only with --force)."""
    names = ["report.html", "timeline.png", "trajectories.png", "bar.png"]
    found = [n for n in names if (folder / n).exists()]
    return found + sorted(p.name for p in folder.glob("configuration-*.png"))


def _svg(fig: MplFigure, path: Path) -> str:
    from cfgplan.sim.drawing import save

    save(fig, path)
    buffer = io.StringIO()
    import matplotlib

    with matplotlib.rc_context({"svg.hashsalt": "cfgplan", "svg.fonttype": "path"}):
        fig.savefig(buffer, format="svg", metadata={"Date": None, "Creator": None})
    return buffer.getvalue()


def _facts(story: Story, source: Source) -> list[str]:
    read = "an MCAP recording" if source.mcap else "a trace"
    names = ", ".join(str(f) for f in source.files)
    out = [f"From {read}: {names} ({len(source.records)} events)."]
    out.append(f"Robots: {', '.join(story.robots)}; {story.end:.1f} s ({story.clock}).")
    switches = story.of("switch")
    failures = story.of("failure")
    out.append(
        f"{len(story.configurations())} configuration(s); {len(switches)} switch(es), "
        f"{len(failures)} failure(s), {len(story.of('recovery'))} recovery(ies)."
    )
    for step in story.steps:
        done = (
            f"accomplished at {step.achieved:g} s"
            if step.achieved is not None
            else "not accomplished"
        )
        out.append(f"Step {step.goal}: {done}.")
    return out


def make_report(paths: Sequence[Path], out: Path, options: ReportOptions | None = None) -> Made:
    """Read the run, draw every picture, write the page (module docstring)."""
    from cfgplan.sim.diagrams import draw_story
    from cfgplan.sim.timeline import timeline_figure

    options = options or ReportOptions()
    source = read_run(paths)
    story = from_records(source.records, source.summary)
    made = Made(story=story)
    figures = [
        Figure(
            "timeline",
            "Configurations over time",
            _svg(timeline_figure(story), out / "timeline.png"),
            "Bars are numbered like the configuration-N diagrams; dashed lines are switches.",
        )
    ]
    made.files.append("timeline.png")
    for number, svg in draw_story(story, out).items():
        made.files.append(f"configuration-{number}.png")
        span = story.configurations()[number]
        figures.append(
            Figure(
                f"configuration-{number}",
                f"Configuration #{number}",
                svg,
                f"{span.goal or 'the task'}, first from {span.start:g} s",
            )
        )
    if source.summary is not None and options.replay:
        again = replay(source)
        if again.run is None:
            made.notes.append(f"No trajectories: {again.why}.")
        else:
            from cfgplan.sim.barplot import bar_figure
            from cfgplan.sim.trajectories import trajectories_figure

            svg = _svg(trajectories_figure(again.run), out / "trajectories.png")
            made.files.append("trajectories.png")
            figures.append(
                Figure(
                    "trajectories",
                    "Trajectories",
                    svg,
                    "Replayed from the seed; the same trace, event for event.",
                )
            )
            bar = bar_figure(again.run)
            if bar is not None:
                figures.append(Figure("bar", "The bar's length", _svg(bar, out / "bar.png")))
                made.files.append("bar.png")
    elif source.other_topics:
        made.notes.append(
            "Not drawn: " + ", ".join(f"{t} ({n})" for t, n in sorted(source.other_topics.items()))
        )
    text = page(story, figures, _facts(story, source), made.notes)
    (out / "report.html").write_text(text, encoding="utf-8")
    made.files.append("report.html")
    return made
