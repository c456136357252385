"""What a ``cfgplan`` command pays from process start to exit:
``python -m benchmarks.startup`` prints a table.

Each row is a command line run as a fresh process (``python -m cfgplan ...``,
what the console script runs), timed from start to exit; the table shows the
best and the median of ``--repeats`` runs, each over the bare interpreter
(``python -c pass``) and over the floor. The targets: ``--version`` and
``--help`` within 2x the bare interpreter; ``plan`` on cross-door 6.2.2
within 1.2x the floor, the last row (:data:`FLOOR`): typer, pydantic, rich
and Lark imported, nothing of cfgplan, and one pydantic model defined
(:data:`ONE_MODEL`) — what any program built on the design's libraries pays
before it does anything. The row before it is the same without the model.
``--against REV`` runs cfgplan at git revision REV (checked out into a
temporary folder as :func:`benchmarks.run.checkout` does) side by side: each repeat runs every
row under both, in turn, so that a machine loaded by other work slows both
alike; it also says whether both printed the same.

Bytecode is cached, as in an installed package (in a temporary
``pycache_prefix``, whatever ``PYTHONDONTWRITEBYTECODE`` says), and so is the
parser (a temporary ``XDG_CACHE_HOME``): an untimed run of every row fills
both first. The measured processes have no terminal, so the help is as wide
as on an 80-column one.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

from benchmarks.run import ROOT, checkout, machine

CROSS = ("domains/cross-door/domain.lisp", "domains/cross-door/state-6.2.2-step1.lisp")

ONE_MODEL = "import pydantic; pydantic.create_model('One', x=(int, 0))"
"""The first model a process defines loads what pydantic leaves until then
(its fields, types and plugin loader, which imports ``importlib.metadata``):
``cfgplan plan`` defines its IR's models, so this is part of its floor."""

ROWS: list[tuple[str, list[str]]] = [
    ("bare interpreter", ["-c", "pass"]),
    ("cfgplan --version", ["-m", "cfgplan", "--version"]),
    ("cfgplan --help", ["-m", "cfgplan", "--help"]),
    ("cfgplan (no arguments)", ["-m", "cfgplan"]),
    ("cfgplan plan --help", ["-m", "cfgplan", "plan", "--help"]),
    ("cfgplan check cross-door 6.2.2", ["-m", "cfgplan", "check", *CROSS]),
    ("cfgplan plan cross-door 6.2.2", ["-m", "cfgplan", "plan", *CROSS]),
    (
        "the libraries plan loads, alone",
        ["-c", "import typer.main, pydantic.main, rich.console, rich.table, lark.lark"],
    ),
    (
        "the same, and one pydantic model defined",
        ["-c", f"import typer.main, rich.console, rich.table, lark.lark; {ONE_MODEL}"],
    ),
]
"""What is measured: a name, and the interpreter's arguments (run from the
tree being measured, so that ``-m cfgplan`` finds that tree's cfgplan)."""

FLOOR = len(ROWS) - 1
"""The row of the floor: the libraries ``plan`` loads and one model (module docstring)."""

TARGETS = {"cfgplan plan cross-door 6.2.2": 1.2}
"""Rows with a target, as a multiple of the floor's best."""


@dataclass
class Runs:
    """The seconds each run of one command line took, and what it printed."""

    seconds: list[float] = field(default_factory=list)
    output: tuple[int, str, str] | None = None

    @property
    def best(self) -> float:
        return min(self.seconds)

    @property
    def median(self) -> float:
        return statistics.median(self.seconds)


def environment(scratch: Path) -> dict[str, str]:
    """This environment with bytecode and the parser cached under ``scratch``."""
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONDONTWRITEBYTECODE", "COLUMNS")}
    env["PYTHONPYCACHEPREFIX"] = str(scratch / "pycache")
    env["XDG_CACHE_HOME"] = str(scratch / "cache")
    return env


def run_once(args: list[str], cwd: Path, env: dict[str, str], runs: Runs) -> None:
    """Run ``python ARGS`` in ``cwd`` once, adding its time and output to ``runs``."""
    started = time.perf_counter()
    done = subprocess.run(
        [sys.executable, *args], cwd=cwd, env=env, capture_output=True, text=True, timeout=120
    )
    runs.seconds.append(time.perf_counter() - started)
    runs.output = (done.returncode, done.stdout, done.stderr)


def measure(trees: list[Path], repeats: int, env: dict[str, str]) -> list[list[Runs]]:
    """For each row, the runs of each tree; one untimed run of each first."""
    table = [[Runs() for _ in trees] for _ in ROWS]
    for _, args in ROWS:  # fills the bytecode and parser caches
        for tree in trees:
            run_once(args, tree, env, Runs())
    for _ in range(repeats):
        for (_, args), cells in zip(ROWS, table, strict=True):
            for tree, runs in zip(trees, cells, strict=True):
                run_once(args, tree, env, runs)
    return table


def ms(seconds: float) -> str:
    return f"{seconds * 1000:.0f}"


def print_table(rev: str | None, table: list[list[Runs]], repeats: int) -> None:
    print(f"- machine: {machine()}")
    print(f"- process start to exit, {repeats} runs each, in turn; ms")
    print()
    bare, floor = table[0], table[FLOOR]
    columns = ["what"]
    if rev is not None:
        columns += [f"best {rev}", f"median {rev}", f"best/bare {rev}", f"best/floor {rev}"]
    columns += ["best", "median", "best/bare", "best/floor"]
    if rev is not None:
        columns += [f"best / best {rev}", "same output"]
    print("| " + " | ".join(columns) + " |")
    print("|" + "---|" * len(columns))
    for (name, _), cells in zip(ROWS, table, strict=True):
        row = [name]
        for runs, base, under in zip(cells, bare, floor, strict=True):
            row += [ms(runs.best), ms(runs.median), f"{runs.best / base.best:.1f}x"]
            row += [f"{runs.best / under.best:.2f}x"]
        if rev is not None:
            old, new = cells
            row += [f"{new.best / old.best:.2f}", "yes" if old.output == new.output else "no"]
        print("| " + " | ".join(row) + " |", flush=True)
    for name, target in TARGETS.items():
        runs = table[[n for n, _ in ROWS].index(name)][-1]
        ratio = runs.best / floor[-1].best
        verdict = "met" if ratio <= target else "not met"
        print(f"\n{name}: {ratio:.2f}x the floor (target {target}x: {verdict})")


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0] if __doc__ else None)
    parser.add_argument("--repeats", type=int, default=15, help="timed runs of each row")
    parser.add_argument(
        "--against",
        metavar="REV",
        help="run cfgplan at this git revision side by side (e.g. fa84306)",
    )
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        scratch = Path(tmp)
        trees = [ROOT]
        if args.against:
            trees = [checkout(args.against, scratch / "against") / "tree", ROOT]
        table = measure(trees, args.repeats, environment(scratch))
    print_table(args.against, table, args.repeats)


if __name__ == "__main__":
    main()
