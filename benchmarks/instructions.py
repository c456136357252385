"""Instructions per warm planning run ("instruction counts where
timing is noise"): ``python -m benchmarks.instructions`` prints a table.

For each instance, two fresh processes run under valgrind's callgrind, each
reading the problem and planning its cheapest configuration once untimed
(the compiled task's caches filled, as the warm "top-1 ms" of
``benchmarks.run``); one then plans it ``--runs`` more times. The difference
of their instruction counts (Ir), divided by ``--runs``, is one warm
planning run's: reading, imports and exit cancel out. Python's string hashes
are fixed (``PYTHONHASHSEED=0``), so a count repeats to within a fraction of
a percent where a time on a shared machine may move by tens. ``--against
REV`` adds the count of cfgplan at git revision REV, checked out as
``benchmarks.run`` does (:func:`benchmarks.run.checkout`), side by side.

Needs ``valgrind`` (Debian: ``apt-get install valgrind``); callgrind runs
Python some fifty times slower, so the default instances are the small ones,
whose planning takes milliseconds and whose times are mostly noise.
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

from benchmarks.instances import Instance, by_name, problem_files

__all__ = ["NAMES", "Options", "count", "main", "plan_runs", "warm"]

NAMES = (
    "cross-door 6.2.2",
    "carry-bar 6.3.2",
    "build-wall 6.4",
    "relay D=4 W=4 V=3",
    "ecology N=6 R=2 C=1",
    "media-tight N=4 R=2 C=1",
    "fusion M=4 V=3 P=4 H=3",
    "chain D=8",
    "delegation N=4",
    "dag D=5",
    "conversion D=4",
    "gateway N=4 D=4",
)
"""The instances counted by default, by name in :data:`benchmarks.instances.INSTANCES`."""


@dataclass(frozen=True)
class Options:
    """How to count: the warm runs counted, and how long one process under
    callgrind may take before it is stopped."""

    runs: int = 3
    timeout: float = 1800.0


def plan_runs(instance: Instance, runs: int) -> None:
    """In this process: read ``instance``, plan its cheapest configuration
    once, then ``runs`` times more (what callgrind counts)."""
    from cfgplan.planner.plan import Run
    from cfgplan.problem import load

    with tempfile.TemporaryDirectory() as tmp:
        problem = load(*problem_files(instance, Path(tmp)))
    for _ in range(1 + runs):
        list(Run(problem.task, problem.goal_call, limit=1))


def _callgrind(name: str, runs: int, options: Options, against: Path | None) -> int:
    """The instructions of one process running :func:`plan_runs`."""
    from benchmarks.run import harness_command

    command, cwd = harness_command("instructions", ["--one", name, str(runs)], against)
    valgrind = ["valgrind", "--tool=callgrind", "--callgrind-out-file=/dev/null"]
    out = subprocess.run(
        [*valgrind, *command],
        cwd=cwd,
        env={**os.environ, "PYTHONHASHSEED": "0"},
        capture_output=True,
        text=True,
        check=True,
        timeout=options.timeout,
    )
    found = re.search(r"Collected : (\d+)", out.stderr)
    if found is None:
        raise SystemExit(f"callgrind printed no count:\n{out.stderr[-2000:]}")
    return int(found.group(1))


def warm(name: str, against: Path | None = None) -> None:
    """Run :func:`plan_runs` of ``name`` once, uncounted, so that the counted
    processes find the tree's bytecode (and the parser's tables) written:
    else the first of them compiles every module it imports, and its count
    is that of compiling (a tree checked out by ``--against`` is fresh)."""
    from benchmarks.run import harness_command

    command, cwd = harness_command("instructions", ["--one", name, "0"], against)
    subprocess.run(command, cwd=cwd, capture_output=True, check=True)


def count(name: str, options: Options, against: Path | None = None) -> float:
    """Instructions of one warm planning run of instance ``name``; with
    ``against`` (a folder made by :func:`benchmarks.run.checkout`), of the
    cfgplan of that tree."""
    more = _callgrind(name, options.runs, options, against)
    base = _callgrind(name, 0, options, against)
    return (more - base) / options.runs


def _millions(n: float) -> str:
    return f"{n / 1e6:.2f}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--one", nargs=2, metavar=("NAME", "RUNS"), help=argparse.SUPPRESS)
    parser.add_argument("--runs", type=int, default=3, help="warm runs counted (default 3)")
    parser.add_argument(
        "--only",
        action="append",
        metavar="NAME",
        help="count this instance (repeatable; default: the small ones)",
    )
    parser.add_argument(
        "--against", metavar="REV", help="compare with cfgplan at this git revision"
    )
    parser.add_argument(
        "--markdown",
        type=Path,
        metavar="FILE",
        help="also write the table as the documentation's page of instruction counts",
    )
    args = parser.parse_args()
    if args.one:
        name, runs = args.one
        plan_runs(by_name(name), int(runs))
        return
    if args.runs < 1:
        parser.error("--runs takes a number >= 1")
    if shutil.which("valgrind") is None:
        missing = "cfgplan: valgrind is not installed (Debian: apt-get install valgrind)"
        print(missing, file=sys.stderr)
        raise SystemExit(1)
    names = tuple(args.only or NAMES)
    for name in names:
        by_name(name)
    from benchmarks.run import checkout, machine

    options = Options(runs=args.runs)
    print(f"machine: {machine()}")
    print(f"instructions (callgrind Ir) per warm top-1 planning run, {options.runs} counted\n")
    columns = ["instance", "M instructions"]
    if args.against:
        columns = ["instance", f"M instructions {args.against}", "M instructions now", "now / then"]
    table: list[str] = []

    def show(line: str) -> None:
        print(line, flush=True)
        table.append(line)

    show("| " + " | ".join(columns) + " |")
    show("|" + "---|" * len(columns))
    with tempfile.TemporaryDirectory() as tmp:
        against = None
        if args.against:
            try:
                against = checkout(args.against, Path(tmp))
            except subprocess.CalledProcessError:
                print(f"cfgplan: no git revision {args.against!r} here", file=sys.stderr)
                raise SystemExit(1) from None
        warm(names[0])
        if against is not None:
            warm(names[0], against)
        for name in names:
            now = count(name, options)
            if against is None:
                show(f"| {name} | {_millions(now)} |")
                continue
            then = count(name, options, against)
            cells = [name, _millions(then), _millions(now), f"{now / then:.3f}"]
            show("| " + " | ".join(cells) + " |")
    if args.markdown:
        from benchmarks.page import instructions_page

        args.markdown.write_text(
            instructions_page(table, machine(), sys.argv[1:]), encoding="utf-8"
        )
        print(f"\nwrote {args.markdown}")


if __name__ == "__main__":
    main()
