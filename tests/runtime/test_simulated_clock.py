"""The runtime's extension points for simulation: a society on a clock of its
own, a loop that never pauses, robots that join on that clock, and a
self-reconfiguring society that plans between cycles (no thread)."""

from __future__ import annotations

from pathlib import Path

from cfgplan.backends.part import runtime_part
from cfgplan.backends.wiring import deploy
from cfgplan.planner import plan
from cfgplan.problem import load
from cfgplan.reconfigure.local import adapt
from cfgplan.runtime import Registry, functionality, society
from cfgplan.runtime.events import Adaptation
from cfgplan.runtime.faults import parse_injection

ROOT = Path(__file__).resolve().parents[2]
DOMAIN = ROOT / "domains" / "cross-door" / "domain.lisp"
STATE = ROOT / "domains" / "cross-door" / "state-6.2.2-step2.lisp"


class Clock:
    """Simulated seconds, advanced only by the loop's ``between`` hook."""

    def __init__(self) -> None:
        self.t = 0.0

    def __call__(self) -> float:
        return self.t


def _registry(seen: list[float], clock: Clock) -> Registry:
    """The cross-door example's implementations, with a cross-door that notes when it runs."""
    registry = Registry.load(ROOT / "examples" / "cross-door" / "impl.py")
    found = {name: registry.lookup(name) for name in registry.names()}

    @functionality("cross-door")
    def cross(door: str, pos: object, orient: object) -> None:
        seen.append(clock())

    found["cross-door"] = cross
    return Registry(found.values())


def test_a_society_on_a_simulated_clock_runs_on_its_beat_without_pausing() -> None:
    problem = load(DOMAIN, STATE)
    (config,), _ = plan(problem.task, problem.goal_call, limit=1)
    clock = Clock()
    seen: list[float] = []
    parts = [runtime_part(p) for p in deploy(config, problem.domain)]
    running = society(parts, _registry(seen, clock), clock=clock, paced=False)
    passes: list[float] = []

    def between(cycle: int, elapsed: float) -> None:
        passes.append(elapsed)
        clock.t = round(clock.t + 0.1, 9)

    reason = running.run(0, 10.0, duration=5.0, budget=None, between=between)
    assert reason == "duration"
    assert len(passes) == 50  # 5 simulated seconds at 10 a second
    assert all(r.clock is clock for r in running.robots)
    # cross-door ran on every beat once the data reached it, at simulated times
    assert seen[0] == 0.1 and seen[-1] == 4.9 and len(seen) == 49
    # a robot that joins takes the society's clock (a switch that needs a new robot)
    assert running.clock is clock


def test_adapt_plans_between_cycles_on_the_simulated_clock() -> None:
    problem = load(DOMAIN, STATE)
    (config,), _ = plan(problem.task, problem.goal_call, limit=1)
    clock = Clock()
    parts = [runtime_part(p) for p in deploy(config, problem.domain)]
    registry = _registry([], clock)
    running = society(parts, registry, clock=clock, paced=False)
    fault = parse_injection("fail compass(Emil) at 3.5s")  # simulated seconds
    hooks = adapt(
        running,
        registry,
        problem.task,
        problem.domain,
        problem.goal_call,
        config,
        (fault,),
        clock=clock,
        ahead=False,
    )
    assert hooks.coordinator.ahead is None and hooks.coordinator.clock is clock
    switches: list[tuple[float, object, object]] = []

    def note(event: object) -> None:
        if isinstance(event, Adaptation) and event.what == "switch":
            switches.append((clock(), event.field("to_cost"), event.field("source")))

    running.subscribe(note)

    def between(cycle: int, elapsed: float) -> None:
        hooks.between(cycle, elapsed)
        clock.t = round(clock.t + 0.1, 9)

    running.run(0, 10.0, duration=5.0, budget=None, before=hooks.before, between=between)
    # the fallbacks were computed one per pass, on this thread, before the
    # fault: the answer is the fallback, at the simulated time of the fault
    assert switches == [(3.5, 47, "fallback")]
