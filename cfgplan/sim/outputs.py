"""What ``cfgplan simulate --out DIR`` writes (docs/tutorials/simulate.md).

* ``summary.json`` — the outcome (:func:`cfgplan.sim.report.summary`);
* ``trace.jsonl`` — every event, one JSON line each (written as the run goes);
* ``trajectories.png`` (Fig. 6.6), ``timeline.png`` (Fig. 6.5);
* ``bar.png`` — with a bar (carry-a-bar): its length over time and its tolerance;
* ``configuration-N.png`` — each configuration used, by the render backend;
* ``animation.gif`` — with ``--animate``.

A folder that already holds a simulation's outputs is written over only
when asked (``force``); nothing else in it is touched.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from cfgplan.diagnostics import error

__all__ = ["OUTPUTS", "prepare", "write_all"]

OUTPUTS = (
    "summary.json",
    "trace.jsonl",
    "trajectories.png",
    "timeline.png",
    "bar.png",
    "animation.gif",
)


def prepare(folder: Path, force: bool) -> None:
    """Make ``folder`` ready to receive the outputs (:class:`CfgplanError` if it cannot)."""
    if folder.exists() and not folder.is_dir():
        raise error(f"{folder} exists and is not a folder")
    if folder.is_dir() and not force:
        found = [n for n in OUTPUTS if (folder / n).exists()]
        found += sorted(p.name for p in folder.glob("configuration-*.png"))
        if found:
            raise error(
                f"{folder} holds the outputs of a simulation ({', '.join(found[:3])}"
                f"{', ...' if len(found) > 3 else ''}); pass --force to overwrite them"
            )
    try:
        folder.mkdir(parents=True, exist_ok=True)
        if force:
            for old in folder.glob("configuration-*.png"):
                old.unlink()
            for name in OUTPUTS:
                (folder / name).unlink(missing_ok=True)
    except OSError as exc:
        raise error(f"cannot write in {folder}: {exc.strerror}") from None


def write_all(run: Any, folder: Path, animate: bool) -> list[str]:
    """Draw the pictures and write the summary; the files written, in order."""
    from cfgplan.sim.barplot import draw_bar
    from cfgplan.sim.diagrams import draw_configurations
    from cfgplan.sim.report import summary
    from cfgplan.sim.story import story_of
    from cfgplan.sim.timeline import draw_timeline
    from cfgplan.sim.trajectories import draw_trajectories

    written = []
    diagrams = draw_configurations(run.recorder.segments, folder)
    written += sorted(set(diagrams.values()))
    draw_trajectories(run, folder / "trajectories.png")
    draw_timeline(story_of(run), folder / "timeline.png")
    written += ["trajectories.png", "timeline.png"]
    if draw_bar(run, folder / "bar.png"):
        written.append("bar.png")
    if animate:
        from cfgplan.sim.animate import animate as draw_animation

        draw_animation(run, folder / "animation.gif")
        written.append("animation.gif")
    document = summary(run, diagrams)
    (folder / "summary.json").write_text(
        json.dumps(document, indent=2, ensure_ascii=False) + "\n", encoding="utf-8"
    )
    return ["summary.json", "trace.jsonl", *written]
