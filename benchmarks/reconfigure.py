"""Reconfiguration, measured: ``python -m benchmarks.reconfigure`` prints two tables (5.5, 7.2).

**Re-planning after a failure.** For a resource of the cheapest
configuration failing, the time to the next configuration, four ways, all
in this process on the same machine in the same run (best of ``--repeats``):

* *cold* — what the thesis's operator did (6.2.2 step 3): the state file
  rewritten without the withdrawn facts, then read, checked, compiled and
  planned from scratch;
* *warm* — the situation derived from the task compiled at the start
  (:func:`cfgplan.reconfigure.situation.derive`: no reading, checking or
  compiling), then planned;
* *again* — the same derived task planned again (a situation seen before:
  the planner's caches per task are warm);
* *fallback* — the reconfigurator's decision when the fallbacks were
  computed ahead of time (a lookup and a relabelling, no search).

**Detection to running again.** The cross-door run of 6.2.2 step 2 with
Emil's compass failing (``--inject 'fail compass(Emil) at cycle N'``),
``--runs`` times each: all robots in one process, and each robot its own
process over Zenoh on loopback (Emil coordinates; prepare/commit). From the
traces: the switch's latency (the failure's detection to the new
configuration installed on every robot), the time from the detection to
``cross-door`` running on data again, and the cycles it went without.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

from cfgplan.notation import atom_text, call_text
from cfgplan.planner import plan
from cfgplan.problem import load
from cfgplan.reconfigure.fallbacks import Resource
from cfgplan.reconfigure.policy import Reconfigurator
from cfgplan.reconfigure.situation import Situation, derive
from cfgplan.runtime.spawn import free_port

ROOT = Path(__file__).resolve().parents[1]
DOMAINS = ROOT / "domains"
IMPL = ROOT / "examples" / "cross-door" / "impl.py"
HERMETIC = "{ scouting: { multicast: { enabled: false }, gossip: { enabled: false } } }"
TIME_LIMIT = 120.0

SCENARIOS: list[tuple[str, str, str, tuple[str, ...]]] = [
    (
        "cross-door 6.2.2 step 2",
        "cross-door/domain.lisp",
        "cross-door/state-6.2.2-step2.lisp",
        ("compass", "Emil"),
    ),
    ("carry-bar 6.3.2", "carry-bar/domain.lisp", "carry-bar/state-6.3.2.lisp", ("laser", "Emil")),
    ("build-wall 6.4", "build-wall/domain.lisp", "build-wall/state-6.4.lisp", ("laser", "Emil")),
]


def best(repeats: int, run: Callable[[], object]) -> float:
    """The best time of ``repeats`` runs, in milliseconds."""
    times = []
    for _ in range(repeats):
        started = time.perf_counter()
        run()
        times.append(time.perf_counter() - started)
    return min(times) * 1000


FAMILY = ("wall K=6 N=20 L=8", (6, 20, 8))
"""A generated build-a-wall (benchmarks/families/wall.py); its first laser fails."""


def replanning(repeats: int) -> list[list[str]]:
    from benchmarks.families import wall

    rows = [
        scenario(name, DOMAINS / d, DOMAINS / s, failed, repeats)
        for name, d, s, failed in SCENARIOS
    ]
    with tempfile.TemporaryDirectory() as folder:
        domain_text, state_text = wall(*FAMILY[1])
        domain, state = Path(folder) / "domain.lisp", Path(folder) / "state.lisp"
        domain.write_text(domain_text)
        state.write_text(state_text)
        rows.append(scenario(FAMILY[0], domain, state, (), repeats))
    return rows


def scenario(
    name: str, domain: Path, state: Path, failed: tuple[str, ...], repeats: int
) -> list[str]:
    """One row of the re-planning table (``failed`` empty: the cheapest
    configuration's first laser)."""
    problem = load(domain, state)
    configs, _ = plan(problem.task, problem.goal_call)
    if not failed:
        failed = next(f.key for f in configs[0].functionalities if f.name == "laser")
    situation = Situation().failing(failed)
    withdrawn = set(situation.withdrawn(problem.task))
    goal = " ".join(problem.goal_call)
    facts = " ".join(atom_text(f) for f in problem.task.facts if f not in withdrawn)
    with tempfile.TemporaryDirectory() as folder:
        edited = Path(folder) / "state.lisp"
        edited.write_text(f"(state {facts})\n(goal ({goal}))\n")

        def cold() -> object:
            p = load(domain, edited)
            return plan(p.task, p.goal_call)

        cold_ms = best(repeats, cold)
    warm_ms = best(repeats, lambda: plan(derive(problem.task, situation), problem.goal_call))
    again = derive(problem.task, situation)
    found, _ = plan(again, problem.goal_call)
    again_ms = best(repeats, lambda: plan(again, problem.goal_call))
    resource = Resource("functionality", instance=failed)
    decide: list[float] = []
    for _ in range(repeats):
        r = Reconfigurator(problem.task, problem.domain, problem.goal_call, configs[0])
        r.compute(r.situation, configs[0], resource)  # what Ahead does in the background
        started = time.perf_counter()
        decision = r.failed(resource)
        decide.append((time.perf_counter() - started) * 1000)
        assert decision.source == "fallback"
    return [
        name,
        call_text(failed),
        f"{configs[0].cost:g} -> {found[0].cost:g}",
        f"{cold_ms:.2f}",
        f"{warm_ms:.2f}",
        f"{again_ms:.2f}",
        f"{min(decide):.3f}",
        f"{cold_ms / warm_ms:.1f}x",
        f"{cold_ms / min(decide):,.0f}x",
    ]


def _records(path: Path) -> list[dict[str, object]]:
    return [json.loads(line) for line in path.read_text().splitlines() if line.strip()]


def _measure(trace: list[dict[str, object]]) -> tuple[float, float, int]:
    """(switch latency, detection -> action ran, cycles without data), seconds."""
    switch = next(r for r in trace if r["event"] == "switch")
    failure = next(r for r in trace if r["event"] == "failure")
    detected = float(switch["t"]) - float(switch["latency"])  # type: ignore[arg-type]
    calls = [
        r
        for r in trace
        if r["event"] == "call"
        and r["functionality"] == "cross-door"
        and int(r["cycle"]) > int(failure["cycle"])  # type: ignore[call-overload]
    ]
    missed = next(i for i, c in enumerate(calls) if c["status"] == "ran")
    ran = float(calls[missed]["t"])  # type: ignore[arg-type]
    return float(switch["latency"]), ran - detected, missed  # type: ignore[arg-type]


def _cfgplan(*args: str) -> list[str]:
    state = [
        str(DOMAINS / "cross-door/domain.lisp"),
        str(DOMAINS / "cross-door/state-6.2.2-step2.lisp"),
    ]
    return [sys.executable, "-m", "cfgplan", "run", *state, "--impl", str(IMPL), *args]


def in_process(rate: float, folder: Path, run: int) -> tuple[float, float, int]:
    trace = folder / f"inprocess-{run}.jsonl"
    args = ["--rate", f"{rate:g}", "--cycles", "30", "--trace", str(trace)]
    args += ["--inject", "fail compass(Emil) at cycle 20"]
    subprocess.run(_cfgplan(*args), check=True, capture_output=True, timeout=TIME_LIMIT)
    return _measure(_records(trace))


def over_zenoh(rate: float, folder: Path, run: int) -> tuple[float, float, int]:
    config = folder / "hermetic.json5"
    config.write_text(HERMETIC)
    port = free_port()
    common = ["--rate", f"{rate:g}", "--zenoh-config", str(config), "--society", f"bench-{run}"]
    emil_trace = folder / f"emil-{run}.jsonl"
    emil = _cfgplan(
        "--robot", "Emil", "--listen", f"tcp/127.0.0.1:{port}", "--cycles", "80",
        "--trace", str(emil_trace), "--inject", "fail compass(Emil) at cycle 60", *common,
    )  # fmt: skip
    pippi = _cfgplan(
        "--robot", "Pippi", "--listen", f"tcp/127.0.0.1:{free_port()}",
        "--connect", f"tcp/127.0.0.1:{port}", *common,
    )  # fmt: skip
    started = [subprocess.Popen(emil, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    try:
        started.append(
            subprocess.Popen(pippi, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        )
        started[0].wait(TIME_LIMIT)
    finally:
        for process in started:
            if process.poll() is None:
                os.kill(process.pid, signal.SIGTERM)
                process.wait(TIME_LIMIT)
    return _measure(_records(emil_trace))


def latency(runs: int, rate: float) -> list[list[str]]:
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        for name, measure in (("in-process", in_process), ("Zenoh, 2 processes", over_zenoh)):
            found = [measure(rate, Path(folder), i) for i in range(runs)]
            switch = [f[0] * 1000 for f in found]
            again = [f[1] * 1000 for f in found]
            rows.append(
                [
                    name,
                    str(runs),
                    f"{statistics.median(switch):.1f}",
                    f"{max(switch):.1f}",
                    f"{statistics.median(again):.1f}",
                    f"{max(again):.1f}",
                    str(max(f[2] for f in found)),
                ]
            )
    base = float(rows[0][2])
    rows[0].append("1.0x")
    rows[1].append(f"{float(rows[1][2]) / base:.1f}x")
    return rows


def table(header: list[str], rows: list[list[str]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(row) + " |" for row in rows]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0] if __doc__ else None)
    parser.add_argument("--repeats", type=int, default=9, help="re-planning: best of N (9)")
    parser.add_argument("--runs", type=int, default=5, help="latency: runs per transport (5)")
    parser.add_argument("--rate", type=float, default=20.0, help="latency: cycles per second (20)")
    args = parser.parse_args(argv)
    print(f"- machine: {platform.system()} {platform.machine()}, {os.cpu_count()} cores; "
          f"Python {platform.python_version()}")  # fmt: skip
    print()
    print(
        table(
            [
                "instance",
                "fails",
                "cost",
                "cold ms",
                "warm ms",
                "again ms",
                "fallback ms",
                "cold / warm",
                "cold / fallback",
            ],
            replanning(args.repeats),
        )
    )
    print()
    print(
        table(
            [
                "robots",
                "runs",
                "switch median ms",
                "switch max ms",
                "data again median ms",
                "data again max ms",
                "cycles without data (max)",
                "switch / in-process",
            ],
            latency(args.runs, args.rate),
        )
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
