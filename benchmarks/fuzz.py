"""Fuzzing cfgplan end to end: ``python -m benchmarks.fuzz --inputs 100000``.

Each input (:mod:`benchmarks.fuzz_inputs`: mutated bundled files, problems
generated from the grammar, deep chains) is written to a domain and a state
file and put through the command line, in process, in a worker subprocess
(:mod:`benchmarks.fuzz_worker`):
``check``; if that passes ``plan -k 3 --format json`` and ``render
--hierarchy``; if a configuration is found ``emit`` in both languages (the
emitted Python must compile) and ``render``. Every command gets a time limit
(5 s) and the worker an address-space cap (2 GiB): a command still running at
its limit is a **time-out** (the worker dumps its stack, then is killed and
replaced); memory running out is reported by cfgplan as a clean error and
counted apart. An exception escaping cfgplan's ``main`` is a **traceback**; a
file written outside ``-o`` is an **escape**. Each finding is attributed to
the package of its innermost cfgplan frame (``planner`` for the search), and
with ``--save DIR`` its domain, state and stack are kept there to become a
regression test.

Printed: a table of outcomes per input (the worst of its commands), per
command and per family, the peak resident memory of the workers, and the
findings. ``--seed`` makes a run reproducible.
"""

from __future__ import annotations

import argparse
import base64
import contextlib
import json
import os
import re
import resource
import select
import signal
import subprocess
import sys
import tempfile
import time
from collections import Counter
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from benchmarks.fuzz_inputs import CASES, Case

ROOT = Path(__file__).resolve().parents[1]
KINDS = (
    "success",
    "clean",
    "memory",
    "traceback",
    "timeout",
    "crash",
    "escape",
    "invalid",
)
"""Outcomes, mildest first; an input counts as the worst of its commands."""
_FRAME = re.compile(r'File "([^"]*cfgplan[/\\]([a-z_]+)[/\\][^"]*)"')
HEADINGS = {
    "success": "successes",
    "clean": "clean errors",
    "memory": "out of memory",
    "traceback": "tracebacks",
    "timeout": "time-outs",
    "crash": "crashes",
    "escape": "escapes",
    "invalid": "invalid code",
}
# -- the parent: generates inputs, watches the worker -------------------------------------------


@dataclass
class Finding:
    kind: str
    command: str
    family: str
    where: str
    detail: str
    case: Case


@dataclass
class Tally:
    inputs: Counter[str] = field(default_factory=Counter)
    commands: dict[str, Counter[str]] = field(default_factory=dict)
    families: dict[str, Counter[str]] = field(default_factory=dict)
    findings: list[Finding] = field(default_factory=list)
    peak_kib: int = 0
    seconds: float = 0.0


def where(detail: str) -> str:
    """The cfgplan package of the innermost cfgplan frame in a traceback or a
    faulthandler dump (``planner``, ``syntax`` ...), or ``?``."""
    frames = _FRAME.findall(detail)
    if not frames:
        return "?"
    first = "most recent call first" in detail  # a faulthandler dump, else a traceback
    innermost: str = (frames[0] if first else frames[-1])[1]
    return innermost


class Worker:
    """One worker subprocess with a memory cap; replaced when it hangs or dies."""

    def __init__(self, time_limit: float, memory_mib: int, folder: Path) -> None:
        self.time_limit = time_limit
        self.memory = memory_mib * 1024 * 1024
        self.dump = folder / f"stack-{os.getpid()}.txt"
        self.errors = folder / f"stderr-{os.getpid()}.txt"
        self.process: subprocess.Popen[bytes] | None = None
        self.buffer = b""
        self.served = 0

    def _start(self) -> subprocess.Popen[bytes]:
        def limit() -> None:
            resource.setrlimit(resource.RLIMIT_AS, (self.memory, self.memory))
            resource.setrlimit(resource.RLIMIT_CORE, (0, 0))

        args = ["--time-limit", str(self.time_limit), "--dump", str(self.dump)]
        self.buffer, self.served = b"", 0
        return subprocess.Popen(
            [sys.executable, "-m", "benchmarks.fuzz_worker", *args],
            cwd=ROOT,
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=open(self.errors, "wb"),  # the child keeps it
            preexec_fn=limit,
        )

    def stop(self) -> None:
        if self.process is not None:
            self.process.kill()
            self.process.wait()
            self.process = None

    def _line(self, deadline: float) -> dict[str, Any] | None:
        assert self.process is not None and self.process.stdout is not None
        fd = self.process.stdout.fileno()
        while b"\n" not in self.buffer:
            remaining = deadline - time.monotonic()
            if remaining <= 0 or not select.select([fd], [], [], remaining)[0]:
                return None
            chunk = os.read(fd, 65536)
            if not chunk:
                return {"eof": True}
            self.buffer += chunk
        line, self.buffer = self.buffer.split(b"\n", 1)
        message: dict[str, Any] = json.loads(line)
        return message

    def run(self, case: Case) -> tuple[dict[str, tuple[str, str]], int]:
        """Each command's (kind, detail) for ``case``, and the worker's peak KiB."""
        if self.process is None or self.served >= 500:
            self.stop()
            self.process = self._start()
        assert self.process.stdin is not None
        job = {
            "domain": base64.b64encode(case.domain).decode(),
            "state": base64.b64encode(case.state).decode(),
        }
        with contextlib.suppress(BrokenPipeError):  # a worker that died at start: a crash
            self.process.stdin.write((json.dumps(job) + "\n").encode())
            self.process.stdin.flush()
        self.served += 1
        results: dict[str, tuple[str, str]] = {}
        current = ""
        while True:
            limit = self.time_limit + 2.0 if current else 60.0  # start-up and writing files
            message = self._line(time.monotonic() + limit)
            if message is None or "eof" in message:
                # At its time limit the worker dumps its stack and exits itself;
                # one that does not (stuck beyond faulthandler) is killed here.
                if message is None:
                    self.process.send_signal(signal.SIGKILL)
                self.process.wait()
                code = self.process.returncode
                detail = self.dump.read_text(errors="replace") if self.dump.exists() else ""
                timed_out = message is None or detail.startswith("Timeout")
                kind = "timeout" if current and timed_out else "crash"
                if kind == "crash" and self.errors.exists():
                    detail += self.errors.read_text(errors="replace")[-6000:]
                self.process = None
                results[current or "start"] = (kind, f"exit {code}\n{detail}")
                return results, 0
            if "start" in message:
                current = message["start"]
            elif "done" in message:
                results[message["done"]] = (message["kind"], message["detail"])
                current = ""
            else:
                return results, int(message["end"])


def campaign(
    inputs: int, seed: int, time_limit: float, memory_mib: int, save: Path | None
) -> Tally:
    """Draw ``inputs`` cases with Hypothesis and run each in a worker."""
    from hypothesis import HealthCheck, Phase, given, settings
    from hypothesis import seed as hypothesis_seed

    tally = Tally()
    start = time.monotonic()
    with tempfile.TemporaryDirectory(prefix="cfgplan-fuzz-parent-") as tmp:
        runner = Worker(time_limit, memory_mib, Path(tmp))

        @hypothesis_seed(seed)
        @settings(
            max_examples=inputs,
            database=None,
            deadline=None,
            phases=[Phase.generate],
            suppress_health_check=list(HealthCheck),
        )
        @given(CASES)
        def one(case: Case) -> None:
            if sum(tally.inputs.values()) >= inputs:
                return
            results, peak = runner.run(case)
            tally.peak_kib = max(tally.peak_kib, peak)
            worst = max((k for k, _ in results.values()), key=KINDS.index, default="success")
            tally.inputs[worst] += 1
            tally.families.setdefault(case.family, Counter())[worst] += 1
            for name, (kind, detail) in results.items():
                tally.commands.setdefault(name, Counter())[kind] += 1
                if kind not in ("success", "clean", "memory"):
                    finding = Finding(kind, name, case.family, where(detail), detail, case)
                    tally.findings.append(finding)
                    if save is not None:
                        keep(finding, save, len(tally.findings))

        try:
            one()
        finally:
            runner.stop()
    tally.seconds = time.monotonic() - start
    return tally


def keep(finding: Finding, folder: Path, number: int) -> None:
    """Save a finding's input and stack for a regression test."""
    place = folder / f"{number:04d}-{finding.kind}-{finding.command}-{finding.where}"
    place.mkdir(parents=True, exist_ok=True)
    (place / "domain.lisp").write_bytes(finding.case.domain)
    (place / "state.lisp").write_bytes(finding.case.state)
    (place / "detail.txt").write_text(finding.detail, errors="replace")


# -- the table ------------------------------------------------------------------------------------


def _row(label: str, counts: Counter[str]) -> str:
    return (
        f"| {label} | {sum(counts.values()):,} | "
        + " | ".join(f"{counts[k]:,}" for k in KINDS)
        + " |"
    )


def table(tally: Tally, args: argparse.Namespace) -> Iterator[str]:
    yield f"- command: python -m benchmarks.fuzz --inputs {args.inputs} --seed {args.seed}"
    yield f"- limits: {args.time_limit:g} s a command, {args.memory_mib:,} MiB address space"
    yield f"- peak resident memory of a worker: {tally.peak_kib / 1024:,.0f} MiB"
    yield f"- wall time: {tally.seconds:,.0f} s"
    yield ""
    head = "| | inputs | " + " | ".join(HEADINGS[k] for k in KINDS) + " |"
    yield head
    yield "|" + "---|" * (len(KINDS) + 2)
    yield _row("all inputs", tally.inputs)
    for family, counts in sorted(tally.families.items()):
        yield _row(f"family {family}", counts)
    for name, counts in tally.commands.items():
        yield _row(f"command {name}", counts)
    if tally.findings:
        yield ""
        by_place = Counter((f.kind, f.command, f.where) for f in tally.findings)
        for (kind, command, place), count in by_place.most_common():
            yield f"- {count:,} {HEADINGS[kind]} in {command}, innermost cfgplan frame in {place}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0] if __doc__ else "")
    parser.add_argument("--inputs", type=int, default=1000)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--time-limit", type=float, default=5.0)
    parser.add_argument("--memory-mib", type=int, default=2048)
    parser.add_argument("--save", type=Path, default=None, help="keep findings here")
    args = parser.parse_args()
    tally = campaign(args.inputs, args.seed, args.time_limit, args.memory_mib, args.save)
    print("\n".join(table(tally, args)))


if __name__ == "__main__":
    main()
