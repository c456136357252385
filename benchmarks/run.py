"""The benchmark suite: ``python -m benchmarks.run`` prints a table.

``--against REV`` prints instead one table comparing this cfgplan with the one
at git revision REV, each instance planned by both in turn by this harness.

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
from dataclasses import dataclass
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]


@dataclass(frozen=True)
class Instance:
    name: str
    kind: str  # "file" | "wall" | "relay"
    args: tuple[object, ...]
    baseline: bool = True  # small enough for the naive baseline
    all_distinct: bool = True  # small enough to list every distinct configuration


INSTANCES = [
    Instance(
        "cross-door 6.2.2", "file", ("cross-door/domain.lisp", "cross-door/state-6.2.2-step1.lisp")
    ),
    Instance("carry-bar 6.3.2", "file", ("carry-bar/domain.lisp", "carry-bar/state-6.3.2.lisp")),
    Instance("build-wall 6.4", "file", ("build-wall/domain.lisp", "build-wall/state-6.4.lisp")),
    Instance("wall K=3 N=4 L=3", "wall", (3, 4, 3)),
    Instance("wall K=4 N=6 L=4", "wall", (4, 6, 4)),
    Instance("wall K=6 N=20 L=8", "wall", (6, 20, 8), baseline=False, all_distinct=False),
    Instance("wall K=8 N=50 L=20", "wall", (8, 50, 20), baseline=False, all_distinct=False),
    Instance("relay D=4 W=4 V=3", "relay", (4, 4, 3)),
    Instance("relay D=5 W=5 V=3", "relay", (5, 5, 3), baseline=False),
    Instance("relay D=8 W=10 V=4", "relay", (8, 10, 4), baseline=False, all_distinct=False),
]


def problem_files(instance: Instance, folder: Path) -> tuple[Path, Path]:
    """The domain and state files of an instance (generated ones into ``folder``)."""
    from benchmarks.families import relay, wall

    if instance.kind == "file":
        domain, state = instance.args
        return ROOT / "domains" / str(domain), ROOT / "domains" / str(state)
    make = wall if instance.kind == "wall" else relay
    domain_text, state_text = make(*instance.args)  # type: ignore[arg-type]
    (folder / "domain.lisp").write_text(domain_text)
    (folder / "state.lisp").write_text(state_text)
    return folder / "domain.lisp", folder / "state.lisp"


def _planner(mode: str) -> Any:
    """What to time: cfgplan's ``plan`` (wherever this version of cfgplan keeps
    it: ``--against`` runs this harness on an older cfgplan) or the baseline."""
    if mode == "baseline":
        from benchmarks.naive import enumerate_all

        return enumerate_all
    try:
        from cfgplan.planner import plan
    except ImportError:  # before the planner package exported it
        from cfgplan.planner.search import plan  # type: ignore[no-redef,attr-defined]
    limit = {"top1": 1, "top10": 10, "all": None}[mode]
    return lambda task, goal: plan(task, goal, limit=limit)[0]


def measure(instance: Instance, mode: str, repeat: int) -> dict[str, object]:
    """One measurement, in this process: mode is top1, top10, all or baseline."""
    from cfgplan.problem import load

    with tempfile.TemporaryDirectory() as tmp:
        domain, state = problem_files(instance, Path(tmp))
        problem = load(domain, state)
    planner = _planner(mode)

    def once() -> tuple[int, float | None]:
        configs = planner(problem.task, problem.goal_call)
        return len(configs), (configs[0].cost if configs else None)

    start = time.perf_counter()
    count, best = once()  # warm-up, untimed
    if time.perf_counter() - start > 2.0:
        repeat = 1  # a long run: once more is enough
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        once()
        times.append(time.perf_counter() - start)
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024  # KiB -> MiB on Linux
    return {"seconds": min(times), "peak_mib": peak, "count": count, "best": best}


def run_one(
    instance: Instance, mode: str, repeat: int, against: Path | None = None
) -> dict[str, object]:
    """Measure in a fresh subprocess; with ``against`` (a folder made by
    :func:`checkout`), the cfgplan of that older version runs under this harness."""
    index = INSTANCES.index(instance)
    command = [sys.executable, "-m", "benchmarks.run", "--one", str(index), mode, str(repeat)]
    cwd = ROOT
    if against is not None:
        # The harness alone in one folder, then the old tree: `benchmarks`
        # is imported from here, `cfgplan` from there.
        code = (
            f"import sys; sys.path[:0] = [{str(against / 'harness')!r}, "
            f"{str(against / 'tree')!r}]; sys.argv[0] = 'benchmarks.run'; "
            "from benchmarks.run import main; main()"
        )
        command = [sys.executable, "-c", code, "--one", str(index), mode, str(repeat)]
        cwd = against
    out = subprocess.run(command, cwd=cwd, capture_output=True, text=True, check=True)
    return json.loads(out.stdout)  # type: ignore[no-any-return]


def checkout(rev: str, folder: Path) -> Path:
    """``folder`` with the tree of ``rev`` (a git revision of this repository)
    in ``tree/`` and this benchmark harness in ``harness/``."""
    (folder / "tree").mkdir(parents=True)
    archive = subprocess.run(
        ["git", "archive", "--format=tar", rev], cwd=ROOT, capture_output=True, check=True
    ).stdout
    subprocess.run(["tar", "-x", "-C", str(folder / "tree")], input=archive, check=True)
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
    return f"{float(seconds) * 1000:.1f}" if isinstance(seconds, (int, float)) else "-"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument(
        "--one", nargs=3, metavar=("INDEX", "MODE", "REPEAT"), help=argparse.SUPPRESS
    )
    parser.add_argument("--only", help="run the instances whose name contains this text")
    parser.add_argument("--no-baseline", action="store_true", help="skip the naive baseline")
    parser.add_argument("--repeat", type=int, default=5, help="timed repeats (best is kept)")
    parser.add_argument(
        "--against",
        metavar="REV",
        help="compare with cfgplan at this git revision, run side by side by this harness",
    )
    args = parser.parse_args()
    if args.one:
        index, mode, repeat = args.one
        print(json.dumps(measure(INSTANCES[int(index)], mode, int(repeat))))
        return
    print(f"machine: {machine()}")
    print("times: planning in-process, warm, best of repeats; memory: peak RSS of the process\n")
    if args.against:
        with tempfile.TemporaryDirectory() as tmp:
            compare(args.against, checkout(args.against, Path(tmp)), args.only, args.repeat)
        return
    columns = [
        "instance",
        "configs",
        "best",
        "top-1 ms",
        "top-10 ms",
        "all distinct ms",
        "baseline ms",
        "baseline / top-1",
        "MiB top-1",
        "MiB all",
        "MiB baseline",
    ]
    print("| " + " | ".join(columns) + " |")
    print("|" + "---|" * len(columns))
    for instance in INSTANCES:
        if args.only and args.only not in instance.name:
            continue
        top1 = run_one(instance, "top1", args.repeat)
        top10 = run_one(instance, "top10", args.repeat)
        every = run_one(instance, "all", args.repeat) if instance.all_distinct else None
        base = None
        if instance.baseline and not args.no_baseline:
            base = run_one(instance, "baseline", 1)
            if base["best"] != top1["best"]:
                raise SystemExit(f"{instance.name}: baseline and cfgplan disagree on the best cost")
        row = [
            instance.name,
            str(every["count"]) if every else "-",
            f"{top1['best']:g}",
            ms(top1["seconds"]),
            ms(top10["seconds"]),
            ms(every["seconds"]) if every else "-",
            ms(base["seconds"]) if base else "-",
            f"{_f(base['seconds']) / _f(top1['seconds']):,.0f}x" if base else "-",
            f"{_f(top1['peak_mib']):.0f}",
            f"{_f(every['peak_mib']):.0f}" if every else "-",
            f"{_f(base['peak_mib']):.0f}" if base else "-",
        ]
        print("| " + " | ".join(row) + " |", flush=True)


def compare(rev: str, against: Path, only: str | None, repeat: int) -> None:
    """One table: each instance planned by cfgplan at ``rev`` and by this
    cfgplan, alternately, in fresh processes; ratios are this / ``rev``."""
    modes = [("top1", "top-1"), ("top10", "top-10"), ("all", "all distinct")]
    columns = ["instance", "configs"]
    for _, name in modes:
        columns += [f"{name} ms {rev}", f"{name} ms", "ratio"]
    columns += [f"MiB {rev}", "MiB"]
    print("| " + " | ".join(columns) + " |")
    print("|" + "---|" * len(columns))
    for instance in INSTANCES:
        if only and only not in instance.name:
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
            if (old["count"], old["best"]) != (new["count"], new["best"]):
                raise SystemExit(f"{instance.name} {mode}: {rev} and this cfgplan disagree")
            ratio = _f(new["seconds"]) / _f(old["seconds"])
            cells += [ms(old["seconds"]), ms(new["seconds"]), f"{ratio:.2f}"]
            peak = (f"{_f(old['peak_mib']):.0f}", f"{_f(new['peak_mib']):.0f}")
            if mode == "all":
                count = str(new["count"])
        row += [count, *cells, *peak]
        print("| " + " | ".join(row) + " |", flush=True)


def _f(value: object) -> float:
    assert isinstance(value, (int, float))
    return float(value)


if __name__ == "__main__":
    main()
