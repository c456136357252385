"""The outcome of a simulation: did the society accomplish its task, and if
not, why — which step, and what the robots lacked.

A scenario succeeds when every step's task was accomplished (its action
reported :data:`~cfgplan.runtime.ACHIEVED`), the bar, if any, never fell,
every block with a target ended aligned with it within its tolerance, and
every robot the scenario names in ``expect.rooms`` ended in that room.

When a step was not accomplished, :func:`why` says which, and what was
missing: the planner's explanation when no configuration was admissible
(the preconditions that failed), else what the step's action was waiting
for and the reasons the functionalities upstream gave for having no data
(:meth:`cfgplan.sim.onboard.Hardware.note`).

:func:`summary` is ``summary.json`` (docs/explanation/simulation.md).
"""

from __future__ import annotations

import math
from typing import Any

from cfgplan.notation import call_text
from cfgplan.reconfigure.suspect import upstream
from cfgplan.sim.blocks import alignment
from cfgplan.sim.onboard import notes
from cfgplan.sim.record import detail
from cfgplan.sim.run import Run

__all__ = ["experiment", "summary", "why"]

NOTE_AGE = 5.0
"""Seconds before the end within which a functionality's note still explains."""


def _r(x: float, digits: int = 3) -> float:
    return round(float(x), digits) + 0.0  # no -0.0


def _cost(x: float) -> int | float:
    return int(x) if float(x).is_integer() else _r(x, 4)


def why(run: Run) -> list[str]:
    """Why the scenario failed (empty when it succeeded)."""
    if run.ended == "none":
        return list(run.why_none)
    out: list[str] = []
    world, s = run.world, run.loaded.scenario
    if run.world.bar_dropped is not None:
        t, d = run.world.bar_dropped
        bar = s.world.bar
        assert bar is not None
        a, b = bar.robots
        out.append(
            f"the bar fell at {t:g} s: {a} and {b} were {d:.2f} m apart "
            f"(it rests on both within {bar.length:g} ± {bar.tolerance:g} m)"
        )
    for i, step in enumerate(run.steps, 1):
        if step.achieved is not None:
            continue
        if step.started is None:
            out.append(
                f"step {i}, {step.goal}, never started: an earlier step was not accomplished"
            )
            continue
        out.append(f"step {i}, {step.goal}, was not accomplished by {world.time:g} s ({run.ended})")
        out += ["  " + line for line in _lacking(run)]
        break
    for name, block in world.blocks.items():
        target = block.spec.target
        if target is None:
            continue
        across, depth, turn = alignment(block, world.walls[target])
        distance, degrees = block.spec.tolerance
        if math.hypot(across, depth) > distance or abs(math.degrees(turn)) > degrees:
            out.append(
                f"{name} is not aligned with {target}: {across * 100:+.1f} cm across, "
                f"{depth * 100:+.1f} cm deep, turned {math.degrees(turn):+.1f} deg "
                f"(tolerance {distance * 100:g} cm, {degrees:g} deg)"
            )
    for robot, room in s.expect.rooms.items():
        found = world.room_of(robot)
        if found != room:
            out.append(f"{robot} ended in {found or 'no room'}, expected in {room}")
    return out


def _lacking(run: Run) -> list[str]:
    """What the running step lacked: the planner's reasons, or the data its action waited for."""
    if run.stopped:
        head = ["no admissible configuration was left; the planner says:"]
        return head + ["  " + w for w in run.why_none] if run.why_none else head
    segments = run.recorder.segments
    config = segments[-1].config if segments else None
    if config is None:
        return []
    out: list[str] = []
    actions = [
        f for f in config.functionalities if not any(c.source == f.label for c in config.channels)
    ]
    known = notes()
    for action in actions:
        call = run.recorder.last_calls.get(action.key)
        instance = call_text(action.key)
        if call is None:
            out.append(f"{instance} never ran")
        elif call.status == "waiting":
            waited = ", ".join(call_text(d) for d in call.waiting)
            out.append(f"{instance} was waiting for {waited}")
        elif call.status == "stale":
            out.append(f"{instance} had stale data: {', '.join(call_text(d) for d in call.stale)}")
        elif call.status == "error":
            out.append(f"{instance} failed: {call.error}")
        else:
            out.append(f"{instance} last {call.status} at {run.world.time:g} s")
        feeding = upstream(config, action.label) | {action.label}
        for f in config.functionalities:
            if f.label not in feeding:
                continue
            note = known.get(call_text(f.key))
            if note is not None and run.world.time - note[0] <= NOTE_AGE:
                out.append(f"  {call_text(f.key)}: {note[1]} (at {note[0]:g} s)")
    return out


def experiment(run: Run) -> str:
    """What ``cfgplan simulate`` was given: a bundled experiment's name, else the
    scenario file (absolute); ``cfgplan report`` replays the run from it."""
    from pathlib import Path

    from cfgplan.sim.run import BUNDLED

    found = Path(run.loaded.file)
    for name, relative in BUNDLED.items():
        if found.as_posix().endswith("/" + relative):
            return name
    return str(found.resolve())


def summary(run: Run, diagrams: dict[int, str] | None = None) -> dict[str, Any]:
    """``summary.json``: the outcome, the steps, the switches, the faults, where everyone went."""
    s = run.loaded.scenario
    world = run.world
    reasons = why(run)
    rec = run.recorder
    configs = []
    for k, seg in enumerate(rec.segments):
        if seg.config is None:
            continue
        configs.append(
            {
                "id": seg.id,
                "goal": call_text(seg.goal),
                "cost": _cost(seg.config.cost),
                "robots": list(seg.config.agents),
                "from": seg.start,
                "until": seg.end,
                "functionalities": [str(f) for f in seg.config.functionalities],
                "diagram": (diagrams or {}).get(k),
            }
        )
    switches = [
        {
            "time": n.t,
            "from_cost": n.record.get("from_cost"),
            "to_cost": n.record.get("to_cost"),  # None: nothing admissible, the society stops
            "reason": n.record.get("cause"),
            "source": n.record.get("source") or None,
        }
        for n in rec.of("switch", "no-configuration")
    ]
    faults = [
        {
            "time": n.t,
            "resource": n.record.get("resource"),
            "how": n.record.get("how"),
            "detected_by": n.record.get("detected_by"),
            "detail": detail(str(n.record.get("detail") or "")),
            "withdrawn": n.record.get("withdrawn", []),
        }
        for n in rec.of("failure")
    ]
    robots = {}
    for name, body in world.bodies.items():
        spec_at = s.robots[name].at
        first = world.samples[0].robots[name]
        robots[name] = {
            "start": [_r(first[0]), _r(first[1]), _r(math.degrees(first[2]), 1)],
            "end": [_r(body.pose[0]), _r(body.pose[1]), _r(math.degrees(body.pose[2]), 1)],
            "room": world.room_of(name),
            "distance": _r(body.travelled),
            "bumps": body.bumps,
            "placed": spec_at is None,
        }
    out: dict[str, Any] = {
        "scenario": s.name,
        "experiment": experiment(run),
        "title": s.title,
        "seed": world.seed,
        "step": s.step,
        "success": not reasons,
        "why": reasons,
        "ended": run.ended,
        "time": _r(world.time, 4),
        "steps": [st.summary() for st in run.steps],
        "configurations": configs,
        "switches": switches,
        "faults": faults,
        "recoveries": [
            {"time": n.t, "resource": n.record.get("resource"), "how": n.record.get("how")}
            for n in rec.of("recovery")
        ],
        "injected": [{"time": n.t, "spec": n.record.get("spec")} for n in rec.of("inject")],
        "world_changes": [{"time": _r(t, 4), "what": w} for t, w in world.changes],
        "robots": robots,
        "distances": {name: r["distance"] for name, r in robots.items()},
    }
    if s.world.bar is not None:
        lengths = [x.bar for x in world.samples if x.bar is not None]
        out["bar"] = {
            "robots": list(s.world.bar.robots),
            "length": s.world.bar.length,
            "tolerance": s.world.bar.tolerance,
            "dropped": world.bar_dropped is not None,
            "dropped_at": None if world.bar_dropped is None else world.bar_dropped[0],
            "min": _r(min(lengths)) if lengths else None,
            "max": _r(max(lengths)) if lengths else None,
        }
    blocks = {}
    for name, block in world.blocks.items():
        entry: dict[str, Any] = {
            "end": [_r(block.pose[0]), _r(block.pose[1]), _r(math.degrees(block.pose[2]), 2)],
            "jams": block.jams,
        }
        if block.spec.target is not None:
            across, depth, turn = alignment(block, world.walls[block.spec.target])
            distance, degrees = block.spec.tolerance
            entry.update(
                target=block.spec.target,
                across=_r(across, 4),
                depth=_r(depth, 4),
                turn_deg=_r(math.degrees(turn), 2),
                aligned=math.hypot(across, depth) <= distance
                and abs(math.degrees(turn)) <= degrees,
            )
        blocks[name] = entry
    if blocks:
        out["blocks"] = blocks
    return out
