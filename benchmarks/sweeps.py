"""Sweeps over the sizes of shapes that fell off cliffs: ``python -m benchmarks.sweeps``
prints a table (``--markdown FILE`` also writes it as a page).

A shape fast at the sizes one picked can fall off a cliff at the next one, so
each family is run at every size of a grid, not at chosen points, and every
figure is ``cfgplan plan ...`` from process start to exit (as a user waits for
it), with the peak resident memory of that process:

- **missions**: a sequence of G independent goals over H helpers
  (:func:`benchmarks.families.missions`), against the sum of its steps
  planned alone (``--goal``, one process each). Target: the sequence within
  2x that sum. ``missions moving``: each mission also moves its robot (a
  postcondition no later step reads). ``patrol``: one robot does every
  mission, from place to place (each step reads where the step before left
  it, and every configuration of a step moves it alike).
- **structured**: randomised fusion over shared, deep filter hierarchies
  (:func:`benchmarks.families.structured`), over the number of pieces, three
  seeds each, without and with media whose capacity binds. Target: 1 s
  (no solver-based planner runs here to compare with).
- **any-delegation**: one generic ``get`` that any of N robots may delegate
  to any other (:func:`benchmarks.families.any_delegation`), with ``-k 1``,
  ``-k 10`` and ``--all``. Targets: 1 s, 5 s, 5 s.

A run stopped at ``--cap`` seconds shows as "> cap". ``--against REV`` also
runs cfgplan at git revision REV (checked out as :func:`benchmarks.run.checkout`
does), each command under both in turn, so that a loaded machine slows both
alike; the two must agree on the best cost.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from benchmarks import families
from benchmarks.run import ROOT, checkout, machine

HELPERS = (10, 20, 30, 40, 50, 60)
GOALS = (2, 5, 10)
ROBOTS = (3, 4, 5, 6)
PIECES = (8, 12, 16, 20, 24)
SEEDS = (1, 2, 3)
MODES = (("-k 1", ["-k", "1"], 1.0), ("-k 10", ["-k", "10"], 5.0), ("--all", ["--all"], 5.0))


@dataclass(frozen=True)
class Measured:
    """One process: how long it took, its peak memory, what it found."""

    seconds: float | None  # None: stopped at the cap, or failed
    mib: float
    best: float | None  # None: nothing (admissible, when it ended)

    def text(self, cap: float) -> str:
        return f"{self.seconds:.2f}" if self.seconds is not None else f"> {cap:g}"


@dataclass(frozen=True)
class Timed:
    """One process run to its end: wall time from start to exit, exit code,
    its own peak RSS and what it printed."""

    seconds: float
    code: int
    mib: float
    text: str


def timed(command: list[str], cwd: Path) -> Timed:
    """Run ``command`` as a fresh process and wait for it (killed, by its pid,
    if the wait is interrupted)."""
    start = time.perf_counter()
    with tempfile.TemporaryFile() as out:
        process = subprocess.Popen(command, cwd=cwd, stdout=out, stderr=subprocess.DEVNULL)
        try:
            _, status, usage = os.wait4(process.pid, 0)
        except BaseException:
            process.kill()
            raise
        took = time.perf_counter() - start
        out.seek(0)
        text = out.read().decode()
    return Timed(took, os.waitstatus_to_exitcode(status), usage.ru_maxrss / 1024, text)


def measured(run: Timed) -> Measured:
    """What a ``cfgplan plan ... --format json`` process found, as :func:`timed` ran it."""
    if run.code not in (0, 3):  # 3: it ended, and nothing is admissible
        return Measured(None, run.mib, None)
    found = json.loads(run.text)
    if found["stats"]["stopped"]:
        return Measured(None, run.mib, None)
    listed = found.get("sequences", found.get("configurations", []))
    best = listed[0].get("total_cost", listed[0].get("cost")) if listed else None
    return Measured(run.seconds, run.mib, best)


def measure(command: list[str], cwd: Path, cap: float) -> Measured:
    """Run ``command`` (a ``cfgplan plan ... --format json``) as a fresh
    process: wall time from start to exit, and its own peak RSS."""
    return measured(timed(command, cwd))


def plan_command(domain: Path, state: Path, cap: float, *more: str) -> list[str]:
    return [sys.executable, "-m", "cfgplan", "plan", str(domain), str(state), *more,
            "--format", "json", "--time-limit", f"{cap:g}"]  # fmt: skip


class Runner:
    """Runs a command with this cfgplan and, with ``against``, with REV's too."""

    def __init__(self, cap: float, against: Path | None) -> None:
        self.cap, self.against = cap, against

    def both(self, command: list[str]) -> tuple[Measured, Measured | None]:
        old = None
        if self.against is not None:
            old = measure(command, self.against / "tree", self.cap)
        new = measure(command, ROOT, self.cap)
        if old and new.best is not None and old.best is not None and old.best != new.best:
            raise SystemExit(f"{command}: this cfgplan and REV disagree on the best cost")
        return new, old


def written(folder: Path, texts: tuple[str, str]) -> tuple[Path, Path]:
    domain, state = folder / "domain.lisp", folder / "state.lisp"
    domain.write_text(texts[0])
    state.write_text(texts[1])
    return domain, state


def mission_rows(run: Runner, kind: str, tmp: Path, rev: str | None) -> Iterator[list[str]]:
    moving, patrol = kind in ("moving", "patrol"), kind == "patrol"
    for goals in GOALS:
        for helpers in HELPERS:
            domain, state = written(tmp, families.missions(goals, helpers, moving, patrol))
            whole, old = run.both(plan_command(domain, state, run.cap, "-k", "1"))
            steps = [f"(mission G{1 if patrol else i} Place{i})" for i in range(1, goals + 1)]
            alone = [
                measure(plan_command(domain, state, run.cap, "-k", "1", "--goal", g), ROOT, run.cap)
                for g in steps
            ]
            times = [m.seconds for m in alone]
            summed = None if None in times else sum(t for t in times if t is not None)
            ratio, verdict = "-", "✗"
            if whole.seconds is not None and summed:
                ratio = f"{whole.seconds / summed:.2f}"
                verdict = "✓" if whole.seconds <= 2 * summed else "✗"
            row = [str(goals), str(helpers), whole.text(run.cap)]
            row += [f"{summed:.2f}" if summed is not None else "-", ratio, verdict]
            row += [f"{whole.mib:.0f}"]
            if rev is not None:
                row += [old.text(run.cap) if old else "-", f"{old.mib:.0f}" if old else "-"]
            yield row


def structured_rows(run: Runner, tmp: Path, rev: str | None) -> Iterator[list[str]]:
    for media in (False, True):
        for pieces in PIECES:
            row = [str(pieces), "yes" if media else "no"]
            for seed in SEEDS:
                texts = families.structured(seed, pieces=pieces, media=media)
                domain, state = written(tmp, texts)
                new, old = run.both(plan_command(domain, state, run.cap, "-k", "1"))
                ok = new.seconds is not None and new.seconds <= 1.0
                row += [new.text(run.cap), "✓" if ok else "✗", f"{new.mib:.0f}"]
                if rev is not None:
                    row += [old.text(run.cap) if old else "-"]
            yield row


def delegation_rows(run: Runner, tmp: Path, rev: str | None) -> Iterator[list[str]]:
    for robots in ROBOTS:
        domain, state = written(tmp, families.any_delegation(robots))
        row = [str(robots)]
        for _, flags, target in MODES:
            new, old = run.both(plan_command(domain, state, run.cap, *flags))
            ok = new.seconds is not None and new.seconds <= target
            row += [new.text(run.cap), "✓" if ok else "✗", f"{new.mib:.0f}"]
            if rev is not None:
                row += [old.text(run.cap) if old else "-"]
        yield row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--cap", type=float, default=30.0, help="seconds a run may take")
    parser.add_argument("--against", metavar="REV", help="also run cfgplan at this revision")
    parser.add_argument(
        "--only",
        choices=["missions", "moving", "patrol", "structured", "delegation"],
        action="append",
        help="one sweep",
    )
    parser.add_argument("--markdown", type=Path, metavar="FILE", help="also write a page")
    parser.add_argument("--note", help="a line for the page: how loaded the machine was")
    args = parser.parse_args()
    only = set(args.only or ["missions", "moving", "patrol", "structured", "delegation"])
    lines = [f"machine: {machine()}; load average {os.getloadavg()[0]:.1f} at the start", ""]
    if args.note:
        lines += [args.note, ""]
    rev = args.against

    def emit(line: str) -> None:
        print(line, flush=True)
        lines.append(line)

    def section(title: str, head: list[str], rows: Iterator[list[str]]) -> None:
        """One sweep's table, each row printed as it is measured."""
        emit(f"### {title}")
        emit("")
        emit("| " + " | ".join(head) + " |")
        emit("|" + "---|" * len(head))
        for row in rows:
            emit("| " + " | ".join(row) + " |")
        emit("")

    with tempfile.TemporaryDirectory() as scratch:
        tmp = Path(scratch)
        against = checkout(rev, tmp / "against") if rev else None
        run = Runner(args.cap, against)
        (tmp / "inputs").mkdir()
        for name in ("missions", "moving", "patrol"):
            if name not in only:
                continue
            title = {"missions": "missions", "moving": "missions moving", "patrol": "patrol"}[name]
            head = ["goals G", "helpers H", "sequence s", "steps alone s", "ratio", "≤ 2x", "MiB"]
            if rev:
                head += [f"sequence s {rev}", f"MiB {rev}"]
            section(title, head, mission_rows(run, name, tmp / "inputs", rev))
        if "structured" in only:
            head = ["pieces", "media"]
            for seed in SEEDS:
                head += [f"seed {seed} s", "≤ 1 s", "MiB"]
                if rev:
                    head += [f"seed {seed} s {rev}"]
            section("structured", head, structured_rows(run, tmp / "inputs", rev))
        if "delegation" in only:
            head = ["robots N"]
            for mode, _, target in MODES:
                head += [f"{mode} s", f"≤ {target:g} s", f"{mode} MiB"]
                if rev:
                    head += [f"{mode} s {rev}"]
            section("any-delegation", head, delegation_rows(run, tmp / "inputs", rev))
    if args.markdown:
        args.markdown.write_text(page(lines, sys.argv[1:]))
        print(f"wrote {args.markdown}")


def page(lines: list[str], argv: list[str]) -> str:
    """The sweeps as a documentation page (the command without its --note,
    which the page says on a line of its own)."""
    shown = [a for i, a in enumerate(argv) if a != "--note" and argv[i - 1 : i] != ["--note"]]
    command = " ".join(["python -m benchmarks.sweeps", *shown])
    head = f"""# Benchmark sweeps

Generated by `{command}`; every figure is `cfgplan plan` from process start
to exit, at every size of each grid (see `benchmarks/sweeps.py` for the
shapes). A cell "> N" is a run stopped at the cap.

"""
    return head + "\n".join(lines) + "\n"


if __name__ == "__main__":
    main()
