"""The benchmark suite: ``python -m benchmarks.run`` prints a table.

``--against REV`` prints instead one table comparing this cfgplan with the one
at git revision REV, each instance planned by both in turn by this harness.
``--markdown FILE`` also writes the table as the documentation's benchmark
page (:mod:`benchmarks.page`): ``--markdown docs/explanation/benchmarks.md``.

Each figure is measured in a fresh subprocess (so peak memory is that run's
own): planning time in-process and warm (the best of a few repeats after one
untimed run; one repeat when that run took over 2 s), and the peak resident
memory of the process. cfgplan and the naive baseline (benchmarks/naive.py:
every derivation, then sort) run side by side on the same machine in the same
invocation; the ratio column is baseline time / cfgplan time for the cheapest
configuration.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from benchmarks.instances import INSTANCES, ROOT, Instance, problem_files

__all__ = ["ROOT", "checkout", "compare", "end_to_end", "machine", "main", "measure", "run_one"]

CAP = 60.0
"""Seconds a run may take before it is stopped and shown as "> CAP"."""


def _stopped(run: Any) -> bool:
    """Whether a run was stopped, however this version of cfgplan says it
    (one status, or the stop reason of older ones)."""
    status = getattr(run, "status", None)
    return bool(status.stopped) if status is not None else bool(run.stopped)


def _planner(mode: str, problem: Any, instance: Instance) -> Any:
    """What to time: cfgplan's ``plan`` (wherever this version of cfgplan keeps
    it: ``--against`` runs this harness on an older cfgplan), its sequence
    search, or the baseline."""
    if instance.sequence:
        from itertools import islice

        from cfgplan.planner.sequence import SequenceSearch

        most = {"top1": 1, "top10": 10}[mode]

        def sequences(task: Any, goal: Any) -> tuple[list[Any], bool]:
            search = SequenceSearch(problem.goal_calls, task)
            search.time_limit = CAP
            found = [
                s.steps[-1].configuration.model_copy(update={"cost": s.total})
                for s in islice(search, most)
            ]
            return found, _stopped(search)

        return sequences
    if mode == "baseline":
        from benchmarks.naive import enumerate_all

        return enumerate_all
    try:
        from cfgplan.planner import plan
    except ImportError:  # before the planner package exported it
        from cfgplan.planner.search import plan  # type: ignore[no-redef,attr-defined]
    limit = {"top1": 1, "top10": 10, "all": None}[mode]

    def planned(task: Any, goal: Any) -> tuple[list[Any], bool]:
        configs, run = plan(task, goal, limit=limit, time_limit=CAP)
        return configs, _stopped(run)

    return planned


def measure(instance: Instance, mode: str, repeat: int) -> dict[str, object]:
    """One measurement, in this process: mode is top1, top10, all or baseline."""
    from cfgplan.problem import load

    with tempfile.TemporaryDirectory() as tmp:
        domain, state = problem_files(instance, Path(tmp))
        problem = load(domain, state)
    planner = _planner(mode, problem, instance)

    def once() -> tuple[int, float | None, bool]:
        result = planner(problem.task, problem.goal_call)
        configs, stopped = result if isinstance(result, tuple) else (result, False)
        return len(configs), (configs[0].cost if configs else None), stopped

    start = time.perf_counter()
    count, best, stopped = once()  # warm-up, untimed (fills the task's caches)
    if time.perf_counter() - start > 2.0:
        repeat = 1  # a long run: once more is enough
    times = []
    for _ in range(0 if stopped else repeat):
        start = time.perf_counter()
        once()
        times.append(time.perf_counter() - start)
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024  # KiB -> MiB on Linux
    seconds = min(times) if times else None
    return {"seconds": seconds, "peak_mib": peak, "count": count, "best": best}


def run_one(
    instance: Instance, mode: str, repeat: int, against: Path | None = None
) -> dict[str, object]:
    """Measure in a fresh subprocess; with ``against`` (a folder made by
    :func:`checkout`), the cfgplan of that older version runs under this harness."""
    index = INSTANCES.index(instance)
    command, cwd = harness_command("run", ["--one", str(index), mode, str(repeat)], against)
    out = subprocess.run(command, cwd=cwd, capture_output=True, text=True, check=True)
    return json.loads(out.stdout)  # type: ignore[no-any-return]


def harness_command(module: str, args: list[str], against: Path | None) -> tuple[list[str], Path]:
    """The command (and its folder) that runs ``benchmarks.<module>``'s
    ``main()`` with ``args`` in a fresh interpreter: with this cfgplan, or with
    ``against``'s (a folder made by :func:`checkout`) under this harness."""
    if against is None:
        return [sys.executable, "-m", f"benchmarks.{module}", *args], ROOT
    # The harness alone in one folder, then the old tree: `benchmarks` is
    # imported from here, `cfgplan` from there.
    code = (
        f"import sys; sys.path[:0] = [{str(against / 'harness')!r}, "
        f"{str(against / 'tree')!r}]; sys.argv[0] = 'benchmarks.{module}'; "
        f"from benchmarks.{module} import main; main()"
    )
    return [sys.executable, "-c", code, *args], against


def checkout(rev: str, folder: Path) -> Path:
    """``folder`` with the tree of ``rev`` (a git revision of this repository)
    in ``tree/`` and this benchmark harness in ``harness/``."""
    (folder / "tree").mkdir(parents=True)
    archive = subprocess.run(
        ["git", "archive", "--format=tar", rev], cwd=ROOT, capture_output=True, check=True
    ).stdout
    subprocess.run(["tar", "-x", "-C", str(folder / "tree")], input=archive, check=True)
    # Its own grammar where it looks for cfgplan.grammar first (the installed
    # package maps that name to this work tree's grammar/ folder).
    grammar, inside = folder / "tree" / "grammar", folder / "tree" / "cfgplan" / "grammar"
    if grammar.is_dir() and not inside.exists():
        shutil.copytree(grammar, inside)
    shutil.copytree(ROOT / "benchmarks", folder / "harness" / "benchmarks")
    (folder / "harness" / "domains").symlink_to(ROOT / "domains")  # the same inputs
    return folder


def machine() -> str:
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return (
        f"{platform.system()} {platform.machine()}, {os.cpu_count()} cores, {cpu}; "
        f"Python {platform.python_version()}"
    )


def ms(seconds: object) -> str:
    """Milliseconds; a run stopped at the cap shows as "> CAP s"."""
    if isinstance(seconds, (int, float)):
        return f"{float(seconds) * 1000:.1f}"
    return f"> {CAP:g} s"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument(
        "--one", nargs=3, metavar=("INDEX", "MODE", "REPEAT"), help=argparse.SUPPRESS
    )
    parser.add_argument(
        "--only",
        action="append",
        metavar="TEXT",
        help="run the instances whose name contains this text (repeatable: any of them)",
    )
    parser.add_argument("--no-baseline", action="store_true", help="skip the naive baseline")
    parser.add_argument("--repeat", type=int, default=5, help="timed repeats (best is kept)")
    parser.add_argument(
        "--against",
        metavar="REV",
        help="compare with cfgplan at this git revision, run side by side by this harness",
    )
    parser.add_argument(
        "--markdown",
        type=Path,
        metavar="FILE",
        help="also write the table as a Markdown page (docs/explanation/benchmarks.md)",
    )
    parser.add_argument("--note", help="a line for the page: how loaded the machine was")
    args = parser.parse_args()
    if args.one:
        index, mode, repeat = args.one
        print(json.dumps(measure(INSTANCES[int(index)], mode, int(repeat))))
        return
    print(f"machine: {machine()}")
    print("times: planning in-process, warm, best of repeats; memory: peak RSS of the process\n")
    table: list[str] = []
    if args.against:
        with tempfile.TemporaryDirectory() as tmp:
            against = checkout(args.against, Path(tmp))
            compare(args.against, against, args.only, args.repeat, table)
    else:
        _table(args, table)
    if args.markdown:
        from benchmarks.page import write

        write(args.markdown, table, machine(), sys.argv[1:], args.note)
        print(f"\nwrote {args.markdown}")


def _selected(instance: Instance, only: list[str] | None) -> bool:
    return not only or any(text in instance.name for text in only)


def _emit(line: str, table: list[str]) -> None:
    """Print a line of the table, and keep it for the page."""
    print(line, flush=True)
    table.append(line)


def _table(args: argparse.Namespace, table: list[str]) -> None:
    columns = [
        "instance",
        "configs",
        "best",
        "top-1 ms",
        "top-10 ms",
        "all distinct ms",
        "baseline ms",
        "baseline / top-1",
        "CLI top-1 ms",
        "MiB top-1",
        "MiB all",
        "MiB baseline",
    ]
    _emit("| " + " | ".join(columns) + " |", table)
    _emit("|" + "---|" * len(columns), table)
    for instance in INSTANCES:
        if _selected(instance, args.only):
            _emit("| " + " | ".join(_row(instance, args)) + " |", table)


def _row(instance: Instance, args: argparse.Namespace) -> list[str]:
    top1 = run_one(instance, "top1", args.repeat)
    top10 = run_one(instance, "top10", args.repeat)
    every = run_one(instance, "all", args.repeat) if instance.all_distinct else None
    base = None
    if instance.baseline and not args.no_baseline:
        base = run_one(instance, "baseline", 1)
        if top1["seconds"] is not None and base["best"] != top1["best"]:
            raise SystemExit(f"{instance.name}: baseline and cfgplan disagree on the best cost")
    ratio = "-"
    if base and top1["seconds"]:
        ratio = f"{_f(base['seconds']) / _f(top1['seconds']):,.0f}x"
    best = top1["best"]
    return [
        instance.name,
        str(every["count"]) if every and every["seconds"] is not None else "-",
        f"{best:g}" if isinstance(best, (int, float)) else "-",
        ms(top1["seconds"]),
        ms(top10["seconds"]),
        ms(every["seconds"]) if every else "-",
        ms(base["seconds"]) if base else "-",
        ratio,
        ms(end_to_end(instance)),
        f"{_f(top1['peak_mib']):.0f}",
        f"{_f(every['peak_mib']):.0f}" if every else "-",
        f"{_f(base['peak_mib']):.0f}" if base else "-",
    ]


def end_to_end(instance: Instance, repeat: int = 3, against: Path | None = None) -> float | None:
    """``cfgplan plan DOMAIN STATE -k 1``, process start to exit, best of a few;
    with ``against`` (a folder made by :func:`checkout`), that older cfgplan's."""
    best: float | None = None
    cwd = ROOT if against is None else against / "tree"  # python -m finds cfgplan there
    with tempfile.TemporaryDirectory() as tmp:
        domain, state = problem_files(instance, Path(tmp))
        command = [sys.executable, "-m", "cfgplan", "plan", str(domain), str(state), "-k", "1"]
        command += ["--format", "json", "--time-limit", f"{CAP:g}"]
        for _ in range(repeat):
            start = time.perf_counter()
            out = subprocess.run(command, cwd=cwd, capture_output=True, text=True)
            took = time.perf_counter() - start
            if out.returncode != 0 or json.loads(out.stdout)["stats"]["stopped"]:
                return None
            best = took if best is None else min(best, took)
    return best


def compare(rev: str, against: Path, only: list[str] | None, repeat: int, table: list[str]) -> None:
    """One table: each instance planned by cfgplan at ``rev`` and by this
    cfgplan, alternately, in fresh processes; ratios are this / ``rev``."""
    modes = [("top1", "top-1"), ("top10", "top-10"), ("all", "all distinct")]
    columns = ["instance", "configs"]
    for _, name in modes:
        columns += [f"{name} ms {rev}", f"{name} ms", "ratio"]
    columns += [f"CLI top-1 ms {rev}", "CLI top-1 ms", "ratio", f"MiB {rev}", "MiB"]
    _emit("| " + " | ".join(columns) + " |", table)
    _emit("|" + "---|" * len(columns), table)
    for instance in INSTANCES:
        if not _selected(instance, only):
            continue
        row = [instance.name]
        cells: list[str] = []
        peak = ("-", "-")
        count = "-"
        for mode, _ in modes:
            if mode == "all" and not instance.all_distinct:
                cells += ["-", "-", "-"]
                continue
            old = run_one(instance, mode, repeat, against)
            new = run_one(instance, mode, repeat)
            finished = old["seconds"] is not None and new["seconds"] is not None
            if finished and (old["count"], old["best"]) != (new["count"], new["best"]):
                raise SystemExit(f"{instance.name} {mode}: {rev} and this cfgplan disagree")
            ratio = "-"
            if old["seconds"] and new["seconds"] is not None:
                ratio = f"{_f(new['seconds']) / _f(old['seconds']):.2f}"
            cells += [ms(old["seconds"]), ms(new["seconds"]), ratio]
            peak = (f"{_f(old['peak_mib']):.0f}", f"{_f(new['peak_mib']):.0f}")
            if mode == "all":
                count = str(new["count"])
        old_cli, new_cli = end_to_end(instance, repeat, against), end_to_end(instance, repeat)
        ratio = f"{new_cli / old_cli:.2f}" if old_cli and new_cli is not None else "-"
        cells += [ms(old_cli), ms(new_cli), ratio]
        row += [count, *cells, *peak]
        _emit("| " + " | ".join(row) + " |", table)


def _f(value: object) -> float:
    assert isinstance(value, (int, float))
    return float(value)


if __name__ == "__main__":
    main()
