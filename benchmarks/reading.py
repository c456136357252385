"""How long reading takes: ``python -m benchmarks.reading`` prints a table.

For each instance, :func:`cfgplan.syntax.reader.read_domain` and
:func:`~cfgplan.syntax.reader.read_state` are timed in-process and warm (one
untimed read of each first, then the best of ``--repeat``), in a fresh
subprocess per instance. ``--against REV`` adds the same figures for cfgplan
at git revision REV, checked out as ``benchmarks.run`` does
(:func:`benchmarks.run.checkout`: that tree's ``cfgplan``, this harness), each
run side by side on the same machine in the same invocation.

The instances: the thesis's cross-door (6.2.2) and the big generated domains
whose reading dominated ``cfgplan plan -k 1`` (chain D=150 and D=200, fusion
M=60), by their names in :data:`benchmarks.instances.INSTANCES`.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from benchmarks.instances import Instance, by_name, problem_files

__all__ = ["NAMES", "Options", "main", "measure", "run_one"]

NAMES = (
    "cross-door 6.2.2",
    "chain D=150",
    "chain D=200",
    "fusion M=60 V=3 P=6 H=6",
)
"""The instances read, by name in :data:`benchmarks.instances.INSTANCES`."""


@dataclass(frozen=True)
class Options:
    """How to measure: timed repeats (the best is kept), and how long one
    subprocess may take before it is stopped."""

    repeat: int = 5
    timeout: float = 300.0


def _best(read: Callable[[], object], repeat: int) -> float:
    read()  # warm: the parser loaded, first-call costs paid
    times = []
    for _ in range(max(1, repeat)):
        start = time.perf_counter()
        read()
        times.append(time.perf_counter() - start)
    return min(times)


def measure(instance: Instance, repeat: int) -> dict[str, float | int]:
    """In this process: the best read_domain and read_state times, and the
    domain file's size."""
    from cfgplan.syntax.reader import read_domain, read_state

    with tempfile.TemporaryDirectory() as tmp:
        domain, state = problem_files(instance, Path(tmp))
        return {
            "domain_s": _best(lambda: read_domain(domain), repeat),
            "state_s": _best(lambda: read_state(state), repeat),
            "bytes": domain.stat().st_size,
        }


def run_one(name: str, options: Options, against: Path | None = None) -> dict[str, float | int]:
    """:func:`measure` in a fresh subprocess; with ``against`` (a folder made by
    :func:`benchmarks.run.checkout`), with the cfgplan of that tree."""
    from benchmarks.run import harness_command

    command, cwd = harness_command("reading", ["--one", name, str(options.repeat)], against)
    out = subprocess.run(
        command, cwd=cwd, capture_output=True, text=True, check=True, timeout=options.timeout
    )
    return json.loads(out.stdout)  # type: ignore[no-any-return]


def _ms(seconds: float | int) -> str:
    return f"{float(seconds) * 1000:.1f}"


def _row(name: str, now: dict[str, float | int], then: dict[str, float | int] | None) -> str:
    total = now["domain_s"] + now["state_s"]
    cells = [name, f"{int(now['bytes']):,}"]
    if then is None:
        cells += [_ms(now["domain_s"]), _ms(now["state_s"]), _ms(total)]
    else:
        before = then["domain_s"] + then["state_s"]
        cells += [_ms(then["domain_s"]), _ms(now["domain_s"])]
        cells += [_ms(then["state_s"]), _ms(now["state_s"])]
        cells += [_ms(before), _ms(total), f"{before / total:.2f}x"]
    return "| " + " | ".join(cells) + " |"


def _header(rev: str | None) -> list[str]:
    if rev is None:
        columns = ["instance", "domain bytes", "domain ms", "state ms", "total ms"]
    else:
        columns = ["instance", "domain bytes", f"domain ms {rev}", "domain ms now"]
        columns += [f"state ms {rev}", "state ms now", f"total ms {rev}", "total ms now"]
        columns += ["speed-up"]
    return ["| " + " | ".join(columns) + " |", "|" + "---|" * len(columns)]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--one", nargs=2, metavar=("NAME", "REPEAT"), help=argparse.SUPPRESS)
    parser.add_argument("--repeat", type=int, default=5, help="timed reads (best is kept)")
    parser.add_argument(
        "--against", metavar="REV", help="compare with cfgplan at this git revision"
    )
    args = parser.parse_args()
    if args.one:
        name, repeat = args.one
        print(json.dumps(measure(by_name(name), int(repeat))))
        return
    if args.repeat < 1:
        parser.error("--repeat takes a number >= 1")
    from benchmarks.run import checkout, machine

    options = Options(repeat=args.repeat)
    print(f"machine: {machine()}")
    print("times: read_domain and read_state in-process, warm, best of repeats\n")
    with tempfile.TemporaryDirectory() as tmp:
        against = None
        if args.against:
            try:
                against = checkout(args.against, Path(tmp))
            except subprocess.CalledProcessError:
                print(f"cfgplan: no git revision {args.against!r} here", file=sys.stderr)
                raise SystemExit(1) from None
        for line in _header(args.against):
            print(line, flush=True)
        for name in NAMES:
            by_name(name)
            then = run_one(name, options, against) if against is not None else None
            now = run_one(name, options)
            print(_row(name, now, then), flush=True)


if __name__ == "__main__":
    main()
