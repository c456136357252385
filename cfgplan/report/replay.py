"""A simulation's poses for its report: run it again, and check it is the same run.

A trace has no poses: robots and blocks are where the simulator put them,
not events. But a simulation is deterministic: one scenario and one seed
give one trace, byte for byte (:mod:`cfgplan.sim.record`). So when a
simulation's ``summary.json`` sits beside the trace, ``cfgplan report``
runs the simulation again — the experiment and the seed the summary names,
for as long as it ran — and uses its world (the trajectories, the bar's
length) only if the new trace is the one given, event for event (but the
planner's explanations, which quote files by the path they were given by). Anything
else (a scenario no longer there, another ``--rank``, an edited trace) is
said in the report, and the report is drawn without trajectories.
"""

from __future__ import annotations

import io
import json
from dataclasses import dataclass
from typing import Any

from cfgplan.diagnostics import CfgplanError
from cfgplan.report.source import Source
from cfgplan.runtime.errors import RunError

__all__ = ["Replayed", "replay"]


@dataclass
class Replayed:
    """The run again (``run``: a :class:`cfgplan.sim.run.Run`), or why not (``why``)."""

    run: Any | None
    why: str = ""


def _same(record: dict[str, Any]) -> dict[str, Any]:
    """What must be equal: all but the planner's explanation of a no-configuration,
    which quotes the domain's file by the path the scenario was given by."""
    if record.get("event") == "no-configuration":
        return {k: v for k, v in record.items() if k != "why"}
    return record


def replay(source: Source) -> Replayed:
    """The simulation of ``source`` run again (module docstring)."""
    summary = source.summary
    if summary is None:
        return Replayed(None, "no summary.json beside the trace: not a simulation's")
    experiment = summary.get("experiment")
    seed = summary.get("seed")
    end = summary.get("time")
    if not isinstance(experiment, str) or not isinstance(seed, int):
        return Replayed(None, "summary.json does not say which simulation to replay")
    try:
        from cfgplan.sim.run import open_scenario, prepare, simulate
    except ImportError as exc:
        return Replayed(None, f"the simulator is not installed ({exc.name})")
    trace = io.StringIO()
    try:
        ready = prepare(open_scenario(experiment))
        # a run cut short by --duration is replayed for as long; any other ran its course
        cut = summary.get("ended") == "duration" and isinstance(end, int | float) and end > 0
        duration = float(end) if cut else None  # type: ignore[arg-type]
        run = simulate(ready, seed=seed, duration=duration, trace=trace)
    except (CfgplanError, RunError) as exc:
        return Replayed(None, f"{experiment} cannot be simulated again: {exc}")
    again = [json.loads(line) for line in trace.getvalue().splitlines() if line.strip()]
    if [_same(r) for r in again] != [_same(r) for r in source.records]:
        return Replayed(None, f"simulating {experiment} again (seed {seed}) gave another trace")
    return Replayed(run)
