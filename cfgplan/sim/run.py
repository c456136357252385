"""The simulation loop: plan, build the society, run it in simulated time.

:func:`simulate` does what ``cfgplan simulate`` does, for a scenario read by
:func:`open_scenario`:

1. read, check and compile the domain, the state and the goals
   (:func:`cfgplan.problem.load`) and check them against the world (every
   robot of the state has a body, standing in the room the state says; every
   door of the state is in the world; every implementation is there);
2. plan the first configuration — of the cheapest sequence of
   configurations when there are several goals (7.3);
3. sort, divide and wire it (chapter 5) and build the robots of
   :mod:`cfgplan.runtime` on the world's clock, monitored and reconfigured
   by :func:`cfgplan.reconfigure.local.adapt` (5.5): the scripted faults are
   the runtime's injections, the world changes the world's;
4. run the runtime's own loop (:meth:`cfgplan.runtime.Society.run`) at one
   cycle per ``step`` of simulated time, no time budget (no threads), the
   fallbacks computed between cycles: after each pass the coordinator acts,
   then the world advances by ``step``. It ends when the last step's task
   is accomplished, the bar falls, or the duration is up.

The same scenario and seed give the same run, to the byte.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import dataclass, field
from importlib import resources
from itertools import islice
from pathlib import Path
from typing import IO

from cfgplan.backends.part import runtime_part
from cfgplan.backends.wiring import deploy
from cfgplan.configuration.model import Configuration
from cfgplan.diagnostics import CfgplanError, Diagnostic, did_you_mean, error
from cfgplan.notation import call_text
from cfgplan.planner import plan
from cfgplan.planner.explain import explain
from cfgplan.planner.sequence import SequenceSearch
from cfgplan.problem import Problem, load
from cfgplan.reconfigure.local import Adaptive, adapt
from cfgplan.runtime.errors import RunError
from cfgplan.runtime.faults import misaimed, parse_injection
from cfgplan.runtime.registry import Registry
from cfgplan.runtime.society import society
from cfgplan.sim.onboard import simulating
from cfgplan.sim.reading import read_scenario
from cfgplan.sim.record import Recorder
from cfgplan.sim.scenario import Loaded, room_of
from cfgplan.sim.world import World

__all__ = ["BUNDLED", "Prepared", "Run", "Step", "open_scenario", "prepare", "simulate"]

BUNDLED = {
    "cross-door": "cross-door/sim-6.2.2.toml",
    "carry-bar": "carry-bar/sim-6.3.2.toml",
    "build-wall": "build-wall/sim-6.4.toml",
}
"""The thesis's experiments, shipped with the domains (``cfgplan.domains``)."""

STALE_PERIODS = 3.0


def open_scenario(experiment: str) -> Loaded:
    """A scenario file, or one of :data:`BUNDLED` by name."""
    path = Path(experiment)
    if path.is_file():
        try:
            text = path.read_bytes().decode("utf-8")
        except (OSError, UnicodeDecodeError) as exc:
            raise error(f"cannot read the scenario {experiment}: {exc}") from None
        return read_scenario(str(path), text, path.parent)
    if experiment in BUNDLED:
        found = resources.files("cfgplan.domains").joinpath(BUNDLED[experiment])
        bundled = Path(str(found))
        text = bundled.read_text("utf-8")
        return read_scenario(str(bundled), text, bundled.parent)
    near = did_you_mean(experiment, BUNDLED)
    raise error(
        f"{experiment}: no such scenario file, nor a bundled scenario",
        hint=near or f"give a scenario file, or one of {', '.join(BUNDLED)}",
    )


@dataclass
class Step:
    """One goal of the scenario: when its configuration started and when its
    task was accomplished (``None``: it was not)."""

    goal: str
    started: float | None = None
    achieved: float | None = None

    def summary(self) -> dict[str, object]:
        """The step as the report (``report.json``) and the story give it."""
        return {
            "goal": self.goal,
            "achieved": self.achieved is not None,
            "started": self.started,
            "time": self.achieved,
        }


@dataclass
class Run:
    """A finished simulation: everything the report and the pictures need."""

    loaded: Loaded
    problem: Problem
    world: World
    recorder: Recorder
    steps: list[Step]
    ended: str  # achieved, dropped, duration, stopped, interrupted
    stopped: bool = False  # nothing admissible was running at the end
    why_none: tuple[str, ...] = ()
    configs: list[Configuration] = field(default_factory=list)


def load_problem(loaded: Loaded) -> Problem:
    """The domain, state and goals of the scenario, read and checked."""
    s = loaded.scenario
    problem = load(loaded.path(s.domain), loaded.path(s.state), s.goals or None)
    problems = _against_world(loaded, problem)
    if problems:
        raise CfgplanError(problems)
    return problem


def _against_world(loaded: Loaded, problem: Problem) -> list[Diagnostic]:
    s = loaded.scenario
    facts = problem.task.facts
    out: list[Diagnostic] = []
    robots = sorted({f[1] for f in facts if len(f) == 2 and f[0] == "robot"})
    state = loaded.scenario.state
    for name in robots:
        if name not in s.robots:
            out.append(
                loaded.problem(
                    f"robots: the state {state} has (robot {name}), the world no body for it",
                    "robots",
                    hint=f"add a [robots.{name}] table with at = [x, y, heading]",
                )
            )
    for name in s.robots:
        if name not in robots:
            out.append(
                loaded.problem(
                    f"robots.{name}: no (robot {name}) in the state {state}", "robots", name
                )
            )
    for door in sorted({f[1] for f in facts if len(f) == 2 and f[0] == "door"}):
        if door not in s.world.doors:
            out.append(
                loaded.problem(
                    f"world.doors: the state has (door {door}), the world does not",
                    "world",
                    "doors",
                )
            )
    pushers = {w for b in s.world.blocks.values() for w in b.pushers.values()}
    missing: dict[str, list[str]] = {}
    for fact in facts:
        if len(fact) != 3 or fact[0] != "in":
            continue
        _, thing, room = fact
        if room not in s.world.rooms:
            missing.setdefault(room, []).append(f"(in {thing} {room})")
        elif thing in s.robots and thing not in pushers and s.robots[thing].at is not None:
            x, y, _ = s.robots[thing].at or (0.0, 0.0, 0.0)
            if room_of({room: s.world.rooms[room]}, x, y) is None:
                out.append(
                    loaded.problem(
                        f"robots.{thing}.at: the state puts {thing} in {room}, "
                        f"({x:g}, {y:g}) is not in it",
                        "robots",
                        thing,
                        "at",
                    )
                )
    for room, said in missing.items():
        out.append(
            loaded.problem(
                f"world.rooms: the state has {', '.join(said)}, the world no room {room}",
                "world",
                "rooms",
            )
        )
    task = problem.task
    for i, text in enumerate(s.faults):
        try:
            wrong = misaimed(parse_injection(text), task.agents, task.functionalities)
        except RunError as exc:
            wrong = exc
        if wrong is not None:
            message = f"faults[{i}]: " + wrong.message.removeprefix("--inject ")
            out.append(Diagnostic("error", message, loaded.where("faults", i), wrong.hint))
    return out


def first_configuration(
    problem: Problem, rank: int = 1
) -> tuple[Configuration | None, tuple[str, ...]]:
    """The configuration to start with — the first step of the sequence of
    ``rank`` (1: the cheapest), or the configuration of that rank — or why
    there is none."""
    goals = problem.goal_calls
    if len(goals) > 1:
        sequences = SequenceSearch(goals, problem.task)
        ranked = list(islice(sequences, rank))
        if len(ranked) == rank:
            return ranked[-1].steps[0].configuration, ()
        if ranked:
            return None, (
                f"there are {len(ranked)} sequences of configurations, none of rank {rank}",
            )
        blocked = sequences.blocked()
        if blocked is None:
            return None, ("no admissible sequence of configurations",)
        step, _, report = blocked
        head = f"step {step + 1}, {call_text(goals[step])}, has no admissible configuration"
        return None, (head, *explain(report, call_text(goals[step])))
    found, search = plan(problem.task, goals[0], limit=rank)
    if len(found) == rank:
        return found[-1], ()
    if found:
        goal = call_text(goals[0])
        return None, (f"{goal} has {len(found)} configurations, none of rank {rank}",)
    return None, (
        f"step 1, {call_text(goals[0])}, has no admissible configuration",
        *explain(search.report, call_text(goals[0])),
    )


def registry_for(loaded: Loaded, problem: Problem) -> Registry:
    """The scenario's implementations, every functionality of the domain among them."""
    spec = loaded.scenario.impl
    if spec.endswith(".py") or "/" in spec:
        spec = str(loaded.path(spec))
    try:
        registry = Registry.load(spec)
        registry.require(f.name.predicate for f in problem.domain.functionalities)
    except RunError as exc:
        if exc.file is not None:
            raise  # a fault in the implementations' own file, at its place
        raise CfgplanError(
            [loaded.problem(f"impl: {exc.message}", "impl", hint=exc.hint)]
        ) from None
    return registry


@dataclass(frozen=True)
class Prepared:
    """A scenario checked against its problem, with its implementations loaded."""

    loaded: Loaded
    problem: Problem
    registry: Registry


def prepare(loaded: Loaded) -> Prepared:
    """Read and check the problem and load the implementations: every input
    error comes out here, before anything is written."""
    problem = load_problem(loaded)
    return Prepared(loaded, problem, registry_for(loaded, problem))


def simulate(
    loaded: Loaded | Prepared,
    *,
    seed: int | None = None,
    duration: float | None = None,
    rank: int | None = None,
    trace: IO[str] | None = None,
    echo: Callable[[str], None] | None = None,
    stop: threading.Event | None = None,
) -> Run:
    """Run the scenario (module docstring). Raises :class:`CfgplanError` for
    bad input and :class:`~cfgplan.runtime.RunError` for implementations that
    cannot be loaded."""
    prepared = loaded if isinstance(loaded, Prepared) else prepare(loaded)
    loaded, problem, registry = prepared.loaded, prepared.problem, prepared.registry
    s = loaded.scenario
    world = World(s, s.seed if seed is None else seed)
    recorder = Recorder(world, trace, echo)
    goals = problem.goal_calls
    steps = [Step(call_text(g)) for g in goals]
    config, why = first_configuration(problem, s.rank if rank is None else rank)
    if config is None:
        return Run(loaded, problem, world, recorder, steps, "none", True, why)
    steps[0].started = 0.0
    parts = [runtime_part(p, config.cost) for p in deploy(config, problem.domain)]
    running = society(parts, registry, clock=world.clock, paced=False)
    running.subscribe(recorder)
    injections = tuple(parse_injection(f) for f in s.faults)
    adaptive = adapt(
        running,
        registry,
        problem.task,
        problem.domain,
        goals[0],
        config,
        injections,
        goals=goals[1:],
        clock=world.clock,
        ahead=False,
    )
    reconfigurator = adaptive.coordinator.reconfigurator
    recorder.running(reconfigurator.id, reconfigurator.running, reconfigurator.goal)
    halt = stop or threading.Event()
    ended: list[str] = []

    def between(cycle: int, elapsed: float) -> None:
        adaptive.between(cycle, elapsed)
        recorder.running(reconfigurator.id, reconfigurator.running, reconfigurator.goal)
        _advance(steps, len(goals) - 1 - len(reconfigurator.goals), adaptive, world.time)
        if adaptive.finished is not None:
            ended.append("achieved")
        elif world.bar_dropped is not None:
            ended.append("dropped")
        if ended:
            halt.set()
            return
        world.step(s.step)

    reason = "interrupted"
    with simulating(world):
        try:
            reason = running.run(
                0,
                1.0 / s.step,
                duration=s.duration if duration is None else duration,
                budget=None,
                stale_periods=STALE_PERIODS,
                stop=halt,
                before=adaptive.before,
                between=between,
            )
        except KeyboardInterrupt:
            reason = "interrupted"
        finally:
            end = ended[0] if ended else reason
            running.close(end)
            recorder.close()
    return Run(
        loaded,
        problem,
        world,
        recorder,
        steps,
        end,
        adaptive.stopped,
        _why_none(recorder) if adaptive.stopped else (),
        [seg.config for seg in recorder.segments if seg.config is not None],
    )


def _advance(steps: list[Step], index: int, adaptive: Adaptive, now: float) -> None:
    """Steps before ``index`` are accomplished; the last one when the run finished."""
    for i, step in enumerate(steps):
        if i < index and step.achieved is None:
            step.achieved = round(now, 4)
        if i == index and step.started is None:
            step.started = round(now, 4)
    if adaptive.finished == "achieved" and steps[-1].achieved is None:
        steps[-1].achieved = round(now, 4)


def _why_none(recorder: Recorder) -> tuple[str, ...]:
    found = recorder.of("no-configuration")
    if not found:
        return ()
    why = found[-1].record.get("why", [])
    return tuple(str(w) for w in why) if isinstance(why, list) else ()
