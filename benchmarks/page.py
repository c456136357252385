"""The benchmark pages of the documentation site, written by the benchmarks.

``python -m benchmarks.run --markdown docs/explanation/benchmarks.md`` writes
the page: what is measured, the families, then the table of that run with the
machine, the date, the revision and the command that made it;
``python -m benchmarks.instructions --against 6332e93 --markdown
docs/explanation/instructions.md`` the page of instruction counts. Nobody
edits the pages by hand; run the benchmark again instead, or, to change only
the words around a run's figures, ``python -m benchmarks.page PAGE``: the page
written again with this module's text, its run's facts and table kept as they
are (nothing is measured).
"""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
import time
from collections.abc import Sequence
from pathlib import Path

from benchmarks.instances import ROOT

INTRO = """\
`python -m benchmarks.run` plans each instance below and prints one table.
Every figure comes from a fresh process: planning time in-process and warm
(the best of several runs after an untimed one, which also fills the compiled
task's caches; one run when a run takes over 2 s; a run is stopped at 60 s,
shown `> 60 s`), the peak resident memory of that process, and "CLI top-1 ms":
`cfgplan plan -k 1 --format json` from process start to exit. That column is
mostly start-up: the interpreter and the libraries cfgplan is built on
(typer, pydantic, rich, Lark) take about 190 ms on this machine before cfgplan
does anything (`python -m benchmarks.startup` measures that floor), and a
loaded machine stretches it: with other work running (load average 1 to 2.4)
cross-door's row took 410 ms, against 215 in the run below. The page says
the machine's load as it ran (where it was recorded): read its times against it.

The **baseline** is the thesis's own strategy, run side by side in the same
invocation: depth-first over every derivation, then sort
(`benchmarks/naive.py`, sharing cfgplan's expansion step); "baseline / top-1"
is its time over cfgplan's time for the cheapest configuration. A test
(`tests/benchmarks/`) checks that both give the same ranked configurations on
every instance small enough for the baseline.

Columns: `configs` is how many distinct configurations exist (when all could
be listed), `best` the cheapest cost, `top-1 ms` / `top-10 ms` / `all distinct
ms` the time to plan the cheapest, the ten cheapest, and every distinct
configuration; `MiB` the peak memory of those runs.

The instances (`benchmarks/instances.py`; families in `benchmarks/families/`):

- the thesis's three experiments: cross-door 6.2.2, carry-bar 6.3.2, build-wall 6.4;
- **wall K N L**: build-a-wall generalised to K pushers among N robots of which
  the last L carry lasers (Appendix A.3 is K=2, N=3, L=2);
- **relay D W V**: an action fed through D levels of methods with V versions
  each (filter locally, or relay from any of the W robots);
- **ecology N R C**: a convoy of N robots in R rooms with C ceiling cameras
  (devices): a covering problem with many equal-cost alternatives;
- **media-tight N R C**: ecology plus an obstacle map per member, streamed raw or
  built on board over media of little capacity, so the derivations cheapest on
  functionalities are communication-inadmissible;
- **fusion M V P H**: one robot fuses M pieces, each from V versions using one
  or two of P sensor kinds, processed on itself or on any of H helpers
  (the CP-SAT comparison planner's time, process start to exit: M=60 2.0 s);
- **chain D**: D levels of 3 versions with equal costs (long plateaus; the
  target: D=150 and D=200 under 1 s, process start to exit);
- **delegation N**: `get` on one robot may delegate to `get` on any other:
  the derivations grow much faster than N!;
- **gateway N D**: N robots each watch a view cropped from one of D ceiling
  cameras and forwarded through a hub, or from a camera of their own;
- **dag D**: D levels, each refining the one below or fusing the two below, so
  every level's derivation is used by the next two (shared
  sub-derivations; the CP-SAT comparison planner, process start to exit: D=18 0.9 s,
  D=24 2.2 s, D=30 2.3 s);
- **conversion D**: one generic `(get ?t ?r)` derives a data type from any type it
  converts from (forward, inverse and skip edges among D+1 types, one sensed),
  pruned only on its own path (recursion; the CP-SAT comparison planner:
  D=28 0.8 s, D=40 1.3 s);
- **deliveries S R**: a sequence of S configurations for R robots.

The shapes that fell off cliffs between the sizes of this table are swept over
every size of a grid on the [sweeps page](benchmark-sweeps.md)
(`python -m benchmarks.sweeps`): sequences of independent goals against their
steps planned alone, delegation to any robot, and randomised structured
domains. The search alone, `cfgplan plan -k 1` as it is (the search raced by
the solver) and a reference planner on an answer-set solver are swept side by
side over every family's sizes on the
[planner page](planner.md#the-race-both-engines-the-first-to-end-answers)
(`python -m benchmarks.engines`).

Planning is one side of a society's speed; the runtime is the other: the
[scale page](scale.md) (`python -m benchmarks.scale`) launches societies of 2
to 50 robots and measures their start-up, idle traffic, memory and the time
to switch when the helper in use is killed, with the router (also with the
society's keys, through its secured router) and in a mesh.

`--against REV` prints instead one table that puts cfgplan at git revision REV
beside this one, each instance planned by both in turn. Where planning takes
milliseconds, times are mostly noise: the [instruction counts](instructions.md)
of the small rows compare revisions instead.
"""


def revision() -> str:
    """The git revision measured (``-dirty`` when the work tree has changes)."""
    out = subprocess.run(
        ["git", "describe", "--always", "--dirty", "--abbrev=10"],
        cwd=ROOT,
        capture_output=True,
        text=True,
    )
    return out.stdout.strip() or "unknown"


def _without_note(command: Sequence[str]) -> list[str]:
    """The command line without ``--note TEXT`` (the page shows the note apart)."""
    out: list[str] = []
    skip = False
    for arg in command:
        if skip:
            skip = False
        elif arg == "--note":
            skip = True
        elif not arg.startswith("--note="):
            out.append(arg)
    return out


def page(
    table: Sequence[str], machine: str, command: Sequence[str], note: str | None = None
) -> str:
    """The page: the introduction, then this run's facts and table."""
    measured = (
        "- times: planning in-process, warm, best of repeats; memory: peak RSS of the process"
    )
    return _document("Benchmarks", INTRO, "run", table, machine, command, measured, note)


INSTRUCTIONS_INTRO = """\
`python -m benchmarks.instructions` counts the instructions one warm planning
run of each small instance takes (callgrind's Ir: two fresh processes under
valgrind, one planning `--runs` more times than the other; the difference
over `--runs` is one run's, reading, imports and exit cancelled out). Where a
planning run takes milliseconds a time moves by tens of percent on a shared
machine; a count repeats to within a fraction of a percent. `--against REV`
counts cfgplan at git revision REV beside this one: the rule is that no row
of the benchmark table be slower than at revision `6332e93`, the baseline
the table is compared with ("instruction counts where timing is noise").

The instances are those of the [benchmark page](benchmarks.md), the small
row of each family.
"""


def instructions_page(table: Sequence[str], machine: str, command: Sequence[str]) -> str:
    """The page of instruction counts (:mod:`benchmarks.instructions`)."""
    measured = "- counted: callgrind Ir per warm top-1 planning run, Python's hashes fixed"
    return _document(
        "Instruction counts", INSTRUCTIONS_INTRO, "instructions", table, machine, command, measured
    )


LOAD_NOT_RECORDED = "not recorded (the run predates the page saying it)"
"""The load of a page written before the page recorded the machine's load."""


def load() -> str:
    """The machine's load average over 1, 5 and 15 minutes (other work slows
    every time on the page), or that it cannot be read here."""
    try:
        one, five, fifteen = os.getloadavg()
    except OSError:
        return "unknown"
    return f"{one:.2f}, {five:.2f}, {fifteen:.2f} (1, 5, 15 minutes; at the end of the run)"


PROCESS_COLUMNS = ("CLI top-1 ms", "MiB top-1", "MiB all", "MiB baseline")
"""The columns of the second table: what a whole process takes (time, memory)."""


def split(table: Sequence[str]) -> list[str]:
    """A run's table as two narrower ones that fit the site's content column:
    the planning times, then the whole process's time and memory (each with
    the instance); a table without those columns is kept as it is."""
    rows = [[c.strip() for c in line.strip().strip("|").split("|")] for line in table]
    if len(rows) < 2 or not set(PROCESS_COLUMNS) <= set(rows[0]):
        return list(table)
    head = rows[0]
    second = [0, *(head.index(c) for c in PROCESS_COLUMNS)]
    first = [i for i in range(len(head)) if i not in second[1:]]

    def part(columns: list[int]) -> list[str]:
        out = []
        for n, row in enumerate(rows):
            cells = ["---" for _ in columns] if n == 1 else [row[i] for i in columns]
            out.append("| " + " | ".join(cells) + " |" if n != 1 else "|" + "---|" * len(columns))
        return out

    return [*part(first), "", "What the whole process takes:", "", *part(second)]


def _document(
    title: str,
    intro: str,
    module: str,
    table: Sequence[str],
    machine: str,
    command: Sequence[str],
    measured: str,
    note: str | None = None,
) -> str:
    """A page written by ``benchmarks.<module>``: ``intro``, then the run's facts and table."""
    shown = shlex.join(["python", "-m", f"benchmarks.{module}", *_without_note(command)])
    when = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    facts = [
        f"- machine: {machine}",
        f"- load average: {load()}",
        f"- date: {when}",
        f"- revision: `{revision()}`",
        measured,
    ]
    if note:
        facts.append(f"- note: {note}")
    return _lines(title, intro, module, facts, split(table), shown)


def _lines(
    title: str, intro: str, module: str, facts: Sequence[str], table: Sequence[str], shown: str
) -> str:
    lines = [
        f"<!-- Written by `python -m benchmarks.{module} --markdown ...`: do not edit by hand. -->",
        "",
        f"# {title}",
        "",
        intro,
        "## The last run",
        "",
        *facts,
        "",
        *table,
        "",
        f"Made with `{shown}`; run it again to regenerate this page.",
    ]
    return "\n".join(lines) + "\n"


def rewrite(path: Path) -> None:
    """Write the page at ``path`` again with this module's words, its run's
    facts (a load added where it was not recorded) and table kept: how the
    page's text changes without measuring again."""
    text = path.read_text(encoding="utf-8")
    module = re.search(r"python -m benchmarks\.(\w+) --markdown", text)
    made = re.search(r"^Made with `(.*)`; run it again", text, re.M)
    run = text.split("## The last run\n", 1)
    if module is None or made is None or len(run) != 2:
        raise SystemExit(f"{path}: not a page benchmarks.page wrote")
    body = run[1].splitlines()
    facts = [line for line in body if line.startswith("- ")]
    if not any(f.startswith("- load average:") for f in facts):
        facts.insert(1, f"- load average: {LOAD_NOT_RECORDED}")
    tables = [line for line in body if line.startswith("|")]
    merged = _merge(tables)
    if module.group(1) == "run":
        title, intro = "Benchmarks", INTRO
    else:
        title, intro = "Instruction counts", INSTRUCTIONS_INTRO
    path.write_text(
        _lines(title, intro, module.group(1), facts, split(merged), made.group(1)),
        encoding="utf-8",
    )


def _merge(lines: Sequence[str]) -> list[str]:
    """The one table :func:`split` made two of (rows by instance, in order), or ``lines``."""
    heads = [
        i for i, line in enumerate(lines) if i + 1 < len(lines) and set(lines[i + 1]) <= set("|-")
    ]
    if len(heads) != 2:
        return list(lines)
    first, second = lines[heads[0] : heads[1]], lines[heads[1] :]
    out = []
    for a, b in zip(first, second, strict=True):
        cells = b.strip().strip("|").split("|")[1:]
        out.append(
            a.rstrip().rstrip("|").rstrip() + " | " + " | ".join(c.strip() for c in cells) + " |"
        )
    out[1] = "|" + "---|" * (len(out[0].strip().strip("|").split("|")))
    return out


if __name__ == "__main__":  # python -m benchmarks.page PAGE...: rewritten, nothing measured
    for name in sys.argv[1:] or ["docs/explanation/benchmarks.md"]:
        rewrite(Path(name))
        print(f"wrote {name}")


def write(
    path: Path,
    table: Sequence[str],
    machine: str,
    command: Sequence[str],
    note: str | None = None,
) -> None:
    path.write_text(page(table, machine, command, note), encoding="utf-8")
