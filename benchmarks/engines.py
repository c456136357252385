"""The two engines side by side: ``python -m benchmarks.engines`` prints a table.

For every size of each shape's grid it runs, each as a fresh process from start
to exit with its own peak memory:

- **search**: ``cfgplan plan D S -k 1`` (the best-first search of 4.5);
- **solver**: the answer-set bracket of the cheapest cost
  (:mod:`cfgplan.planner.solver`), run as ``python -m benchmarks.engines
  --bracket D S``: the relaxation's optimum (a lower bound) and the cheapest
  one-expansion-per-instance answer (an upper bound, a configuration).

A row says whether the bracket closed (the two meet: the cheapest cost is
proven) and whether it agrees with the search where both ended. "> cap" is a
run stopped at ``--cap`` seconds. The shapes are those the search fell off
cliffs on (``structured``, ``overlap``, ``gateway``, fusion with 5 versions) and
those it is fast on (``chain``, ``dag``, ``conversion``, ``any_delegation``).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

from benchmarks import families
from benchmarks.families import weak
from benchmarks.run import ROOT, machine
from benchmarks.sweeps import measure, plan_command, written

Family = Callable[[int], tuple[str, str]]

SHAPES: dict[str, tuple[Family, tuple[int, ...]]] = {
    "structured seed 1": (lambda p: families.structured(1, pieces=p), (8, 12, 16, 20, 24, 30)),
    "structured seed 2": (lambda p: families.structured(2, pieces=p), (8, 12, 16, 20, 24, 30)),
    "structured seed 1, media": (
        lambda p: families.structured(1, pieces=p, media=True),
        (8, 12, 16, 20),
    ),
    "overlap": (weak.overlap, (22, 23, 24, 25, 26, 27, 28, 29, 30, 31)),
    "gateway N, D=5": (lambda n: families.gateway(n, 5), (5, 6, 7, 8, 9)),
    "fusion M, 5 versions": (lambda m: families.fusion(m, 5, 2, 2), (10, 20, 30, 40, 50, 60)),
    "chain": (families.chain, (50, 100, 150, 200)),
    "dag": (families.dag, (12, 18, 24, 30)),
    "conversion": (families.conversion, (12, 20, 28, 40)),
    "any_delegation": (families.any_delegation, (3, 4, 5, 6)),
}


@dataclass(frozen=True)
class Bracketed:
    """One solver process: its time, peak memory and bracket."""

    seconds: float | None  # None: failed
    mib: float
    lower: float | None  # None: the relaxation has no model (nothing is admissible)
    upper: float | None  # None: no answer found


def bracketed(domain: Path, state: Path, cap: float) -> Bracketed:
    command = [sys.executable, "-m", "benchmarks.engines", "--bracket", str(domain), str(state),
               "--cap", f"{cap:g}"]  # fmt: skip
    start = time.perf_counter()
    with tempfile.TemporaryFile() as out:
        process = subprocess.Popen(command, cwd=ROOT, stdout=out, stderr=subprocess.DEVNULL)
        _, status, usage = os.wait4(process.pid, 0)
        took = time.perf_counter() - start
        out.seek(0)
        text = out.read().decode()
    mib = usage.ru_maxrss / 1024
    if os.waitstatus_to_exitcode(status) != 0:
        return Bracketed(None, mib, 0.0, None)
    found = json.loads(text)
    return Bracketed(took, mib, found["lower"], found["upper"])


def bracket_one(domain: Path, state: Path, cap: float) -> None:
    """Print the bracket of one problem as JSON (the solver's process)."""
    from cfgplan.planner.ground import Grounder
    from cfgplan.planner.solver import bracket
    from cfgplan.problem import load

    problem = load(domain, state)
    found = bracket(Grounder(problem.task), problem.goal_call, cap)
    lower = None if found.lower == float("inf") else found.lower
    upper = None if found.upper is None else found.upper.cost
    print(json.dumps({"lower": lower, "upper": upper}))


def rows(cap: float, only: str | None) -> Iterator[list[str]]:
    for name, (make, sizes) in SHAPES.items():
        if only and only not in name:
            continue
        for size in sizes:
            with tempfile.TemporaryDirectory() as tmp:
                domain, state = written(Path(tmp), make(size))
                search = measure(plan_command(domain, state, cap, "-k", "1"), ROOT, cap)
                solver = bracketed(domain, state, cap)
            # closed: the two meet, or the relaxation proved that nothing is admissible
            closed = solver.seconds is not None and solver.lower == solver.upper
            proven = search.best if search.seconds is not None else None
            agree = "" if proven is None or not closed else ("✓" if proven == solver.lower else "✗")
            ratio = (
                f"{solver.seconds / search.seconds:.2f}"
                if search.seconds and solver.seconds and closed
                else ""
            )
            yield [
                name,
                str(size),
                search.text(cap),
                "" if proven is None else f"{proven:g}",
                f"{search.mib:.0f}",
                "failed" if solver.seconds is None else f"{solver.seconds:.2f}",
                "none" if solver.lower is None else f"{solver.lower:g}",
                "" if solver.upper is None else f"{solver.upper:g}",
                "✓" if closed else "✗",
                agree,
                ratio,
                f"{solver.mib:.0f}",
            ]


HEAD = ["shape", "size", "search s", "search cost", "MiB", "solver s", "lower", "upper",
        "closed", "agree", "solver/search", "MiB"]  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--cap", type=float, default=20.0, help="seconds a run may take")
    parser.add_argument("--only", help="only the shapes whose name contains this")
    parser.add_argument("--bracket", nargs=2, type=Path, metavar=("DOMAIN", "STATE"))
    args = parser.parse_args()
    if args.bracket:
        domain, state = args.bracket
        bracket_one(domain, state, args.cap)
        return
    print(machine())
    print(f"load average {os.getloadavg()[0]:.1f} at the start")
    print()
    print("| " + " | ".join(HEAD) + " |")
    print("|" + "---|" * len(HEAD))
    for row in rows(args.cap, args.only):
        print("| " + " | ".join(row) + " |", flush=True)
    print()
    print(f"load average {os.getloadavg()[0]:.1f} at the end")


if __name__ == "__main__":
    main()
