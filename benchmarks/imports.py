"""What a robot pays to start: ``python -m benchmarks.imports`` prints a table.

Each row is a fresh interpreter (``python -c CODE``), timed from start to
exit, best of ``--repeats``; the bare interpreter (``pass``) is the baseline
and the ratio column is each row over it. ``import cfgplan.runtime`` is what
every emitted robot program pays before it runs; ``import zenoh`` what it adds
with ``--transport zenoh``; the command line (typer, rich, pydantic, lark,
the planner) is shown for comparison, whole and as one command loads it
(:func:`cfgplan.cli.app.register`). Bytecode is cached, as in an
installed package (in a temporary ``pycache_prefix``, so the work tree stays
clean, whatever ``PYTHONDONTWRITEBYTECODE`` says); an untimed run fills it.
"""

from __future__ import annotations

import argparse
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

ROWS = [
    ("bare interpreter", "pass"),
    ("import cfgplan.runtime", "import cfgplan.runtime"),
    ("import zenoh", "import zenoh"),
    ("import cfgplan.runtime, zenoh", "import cfgplan.runtime, zenoh"),
    ("import the cfgplan command line", "import cfgplan.cli.commands"),
    (
        "what `cfgplan plan` imports",
        "from cfgplan.cli.app import register; register(['plan'])",
    ),
]


def best_of(code: str, repeats: int, cache: str) -> float:
    """Seconds from start to exit of ``python -c code``, the best of ``repeats``."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    command = [sys.executable, "-X", f"pycache_prefix={cache}", "-c", code]
    best = float("inf")
    for _ in range(repeats):
        started = time.perf_counter()
        subprocess.run(command, cwd=ROOT, env=env, check=True)
        best = min(best, time.perf_counter() - started)
    return best


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0] if __doc__ else None)
    parser.add_argument("--repeats", type=int, default=15)
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as cache:
        best_of("import cfgplan.cli.commands, zenoh", 1, cache)  # fills the bytecode cache
        times = [(name, best_of(code, args.repeats, cache)) for name, code in ROWS]
    bare = times[0][1]
    print(
        f"- machine: {platform.system()} {platform.machine()}; Python {platform.python_version()}"
    )
    print(f"- process start to exit, best of {args.repeats}")
    print()
    print("| what | ms | over the bare interpreter |")
    print("|---|---|---|")
    for name, seconds in times:
        print(f"| {name} | {seconds * 1000:.0f} | {seconds / bare:.1f}x |")


if __name__ == "__main__":
    main()
