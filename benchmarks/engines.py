"""The engines side by side: ``python -m benchmarks.engines`` prints a table.

For every size of each shape's grid (every size between the smallest and the
largest: a sweep, not chosen points) it runs three processes, each timed from
start to exit with its own peak memory:

- **search**: ``cfgplan plan D S -k 1 --engine search`` (the best-first search of
  4.5 alone: ``cfgplan plan`` as it was before the race);
- **cfgplan**: ``cfgplan plan D S -k 1``, the default ``--engine both``: the
  search, and past a moment the solver's process racing it
  (:mod:`cfgplan.planner.solver`); "by" says which engine answered;
- **reference**: a planner built on an answer-set solver over the ground
  instances, one expansion per instance (:func:`cfgplan.planner.solver.upper`,
  run as ``python -m benchmarks.engines --reference D S``): the kind of planner
  the goal is set against.

"goal" is ✓ when cfgplan took at most max(1 s, 2 × the reference's time). The
cost is cfgplan's ("none": it proved that nothing is admissible); where the
reference's differs it is shown after a slash (one expansion per instance can
cost more than the thesis's planner, which expands each occurrence its own way;
never less). The memory of cfgplan is its first
process's: the solver's process, when it is started, is a fork of it and peaks
at about the reference's. "> cap" is a run stopped at ``--cap`` seconds.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

from benchmarks import families
from benchmarks.families import weak
from benchmarks.run import ROOT, machine
from benchmarks.sweeps import Measured, measure, measured, plan_command, timed, written

Family = Callable[[int], tuple[str, str]]

SHAPES: dict[str, tuple[Family, range]] = {
    "structured seed 1": (lambda p: families.structured(1, pieces=p), range(8, 31)),
    "structured seed 2": (lambda p: families.structured(2, pieces=p), range(8, 31)),
    "structured seed 1, media": (
        lambda p: families.structured(1, pieces=p, media=True),
        range(8, 21),
    ),
    "overlap": (weak.overlap, range(22, 32)),
    "gateway N, D=5": (lambda n: families.gateway(n, 5), range(5, 10)),
    "fusion M, 3 versions": (lambda m: families.fusion(m, 3, 2, 2), range(40, 101)),
    "fusion M, 5 versions": (lambda m: families.fusion(m, 5, 2, 2), range(10, 61)),
    "chain": (families.chain, range(50, 201)),
    "dag": (families.dag, range(12, 31)),
    "conversion": (families.conversion, range(12, 41)),
    "any_delegation": (families.any_delegation, range(3, 7)),
}


@dataclass(frozen=True)
class Referenced:
    """The reference's process: its time, peak memory and cost."""

    seconds: float | None  # None: stopped at the cap, or failed
    mib: float
    cost: float | None  # None: no configuration found


def referenced(domain: Path, state: Path, cap: float) -> Referenced:
    command = [sys.executable, "-m", "benchmarks.engines", "--reference", str(domain),
               str(state), "--cap", f"{cap:g}"]  # fmt: skip
    run = timed(command, ROOT)
    if run.code != 0:
        return Referenced(None, run.mib, None)
    found = json.loads(run.text)
    return Referenced(run.seconds if found["ended"] else None, run.mib, found["cost"])


def reference_one(domain: Path, state: Path, cap: float) -> None:
    """Print the reference's answer for one problem as JSON (its own process)."""
    from cfgplan.planner.ground import Grounder
    from cfgplan.planner.solver import upper
    from cfgplan.problem import load

    problem = load(domain, state)
    start = time.perf_counter()
    found = upper(Grounder(problem.task), problem.goal_call, cap)
    ended = time.perf_counter() - start < cap
    print(json.dumps({"cost": None if found is None else found.cost, "ended": ended}))


def answered(command: list[str]) -> tuple[Measured, str]:
    """``command`` measured (:func:`benchmarks.sweeps.measured`), and which engine answered."""
    run = timed(command, ROOT)
    found = measured(run)
    engine = json.loads(run.text)["stats"]["engine"] if found.seconds is not None else ""
    return found, engine


def rows(cap: float, only: str | None, step: int) -> Iterator[list[str]]:
    for name, (make, sizes) in SHAPES.items():
        if only and only not in name:
            continue
        for size in sizes[::step]:
            with tempfile.TemporaryDirectory() as tmp:
                domain, state = written(Path(tmp), make(size))
                search = measure(plan_command(domain, state, cap, "-k", "1", "--engine", "search"),
                                 ROOT, cap)  # fmt: skip
                ours, by = answered(plan_command(domain, state, cap, "-k", "1"))
                ref = referenced(domain, state, cap)
            goal = ""
            if ref.seconds is not None:
                goal = "✓" if ours.seconds and ours.seconds <= max(1.0, 2 * ref.seconds) else "✗"
            elif ours.seconds is not None:
                goal = "✓"  # the reference did not end within the cap
            cost = "" if ours.seconds is None else "none" if ours.best is None else f"{ours.best:g}"
            if ref.seconds is not None and ref.cost != ours.best:
                cost += " / " + ("none" if ref.cost is None else f"{ref.cost:g}")
            yield [
                name,
                str(size),
                search.text(cap),
                ours.text(cap),
                by,
                "> cap" if ref.seconds is None else f"{ref.seconds:.2f}",
                goal,
                cost,
                f"{ours.mib:.0f}",
                f"{ref.mib:.0f}",
            ]


HEAD = ["shape", "size", "search s", "cfgplan s", "by", "reference s", "goal", "cost", "MiB",
        "ref. MiB"]  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--cap", type=float, default=20.0, help="seconds a run may take")
    parser.add_argument("--only", help="only the shapes whose name contains this")
    parser.add_argument("--step", type=int, default=1, help="every STEP-th size (default: all)")
    parser.add_argument("--reference", nargs=2, type=Path, metavar=("DOMAIN", "STATE"))
    args = parser.parse_args()
    if args.reference:
        domain, state = args.reference
        reference_one(domain, state, args.cap)
        return
    print(machine())
    print(f"load average {os.getloadavg()[0]:.1f} at the start")
    print()
    print("| " + " | ".join(HEAD) + " |")
    print("|" + "---|" * len(HEAD))
    for row in rows(args.cap, args.only, args.step):
        print("| " + " | ".join(row) + " |", flush=True)
    print()
    print(f"load average {os.getloadavg()[0]:.1f} at the end")


if __name__ == "__main__":
    main()
