"""The runtime at scale: ``python -m benchmarks.scale`` prints one table.

``cfgplan launch`` of a generated docking society (domains/docking): Vacu,
whose laser failed, must dock, and each of N-1 helpers H1, H2, ... has a
laser that can tell Vacu its pose (any of them serves the goal). For each
size and each topology, side by side in one run on this machine:

* *router* — launch's default: one Zenoh router (``cfgplan router``), every
  robot its client (``--router``);
* *mesh* — ``--topology mesh``: every robot a peer linked to every other.

Columns: the established TCP connections of the whole society (each counted
once), all robots up (every trace has begun) and the goal's first data
(Vacu's ``dock`` ran on a pose) after the launch started, the CPU of every
process of the society and the TCP segments the machine sent per second over
an idle window (nothing else should run), the RSS of a robot process and of
them all, then, killing (SIGKILL) the helper in use, the time to the switch
and to the goal's data again. A run that does not get there within
``--limit`` seconds shows ``-``.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import re
import signal
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from benchmarks.fault_conditions import DOCKING_IMPL

ROOT = Path(__file__).resolve().parents[1]
DOMAIN = ROOT / "domains" / "docking" / "domain.lisp"
TOPOLOGIES = ("router", "mesh")
TICK = os.sysconf("SC_CLK_TCK")
PAGE = os.sysconf("SC_PAGE_SIZE")


def state_text(n: int) -> str:
    """Vacu (no laser) and ``n`` - 1 helpers with lasers, all in the kitchen."""
    helpers = [f"H{k}" for k in range(1, n)]
    facts = ["(robot Vacu)", "(station Charger1)", "(in Vacu Kitchen)", "(in Charger1 Kitchen)"]
    for h in helpers:
        facts += [f"(robot {h})", f"(laser {h})", f"(in {h} Kitchen)"]
    return f"(state {' '.join(facts)})\n(goal (do-dock Vacu Charger1))\n"


@dataclass
class Society:
    """One launch, its output read as it comes."""

    process: subprocess.Popen[str]
    folder: Path
    lines: list[str] = field(default_factory=list)

    def read(self) -> None:
        assert self.process.stdout is not None
        for line in self.process.stdout:
            self.lines.append(line)

    def pids(self) -> dict[str, int]:
        """Each process's newest pid, as the launch says it."""
        found: dict[str, int] = {}
        for m in re.finditer(
            r"^(\w+) +\| \(started(?: again)?: pid (\d+)", "".join(self.lines), re.M
        ):
            found[m[1]] = int(m[2])
        return found

    def trace(self, robot: str) -> list[dict[str, object]]:
        """The complete lines of ``robot``'s trace so far."""
        try:
            text = (self.folder / f"run-{robot.lower()}.jsonl").read_text("utf-8")
        except OSError:
            return []
        return [json.loads(line) for line in text.split("\n")[:-1]]

    def begun(self, robot: str) -> bool:
        """Whether ``robot``'s trace has its first line."""
        try:
            with (self.folder / f"run-{robot.lower()}.jsonl").open("rb") as f:
                return b"\n" in f.read(4096)
        except OSError:
            return False


def _until(found: Callable[[], object], limit: float) -> object | None:
    deadline = time.monotonic() + limit
    while time.monotonic() < deadline:
        got = found()
        if got:
            return got
        time.sleep(0.05)
    return None


def _cpu(pid: int) -> float:
    """Seconds of CPU ``pid`` used (user and system)."""
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except OSError:
        return 0.0
    return (int(fields[11]) + int(fields[12])) / TICK


def _rss(pid: int) -> int:
    try:
        return int(Path(f"/proc/{pid}/statm").read_text().split()[1]) * PAGE
    except OSError:
        return 0


def _sockets(pid: int) -> set[str]:
    out = set()
    try:
        for fd in Path(f"/proc/{pid}/fd").iterdir():
            try:
                target = os.readlink(fd)
            except OSError:
                continue
            if target.startswith("socket:["):
                out.add(target[8:-1])
    except OSError:
        pass
    return out


def connections(pids: list[int]) -> int:
    """Established TCP connections between these processes, each counted once."""
    inodes = set().union(*(_sockets(p) for p in pids)) if pids else set()
    ends = 0
    for table in ("/proc/net/tcp", "/proc/net/tcp6"):
        for line in Path(table).read_text().splitlines()[1:]:
            fields = line.split()
            if fields[3] == "01" and fields[9] in inodes:
                ends += 1
    return ends // 2


def segments() -> int:
    """TCP segments this machine has sent (/proc/net/snmp)."""
    rows = [
        r.split() for r in Path("/proc/net/snmp").read_text().splitlines() if r.startswith("Tcp:")
    ]
    return int(rows[1][rows[0].index("OutSegs")])


def _served(society: Society, after: float) -> float | None:
    for r in society.trace("Vacu"):
        if (
            r.get("event") == "call"
            and r.get("functionality") == "dock"
            and r.get("status") == "ran"
        ):
            t = float(r["t"])  # type: ignore[arg-type]
            if t > after:
                return t
    return None


def measure(n: int, topology: str, limit: float, idle: float) -> list[str]:
    """One row: ``n`` robots, ``topology``."""
    with tempfile.TemporaryDirectory(prefix="cfgplan-scale-") as name:
        folder = Path(name)
        state, impl = folder / "state.lisp", folder / "impl.py"
        state.write_text(state_text(n))
        impl.write_text(DOCKING_IMPL)
        began = time.time()
        process = subprocess.Popen(
            [sys.executable, "-m", "cfgplan", "launch", str(DOMAIN), str(state),
             "--impl", str(impl), "--topology", topology,
             "--trace", str(folder / "run.jsonl"), "--rate", "10"],
            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, cwd=ROOT,
            start_new_session=True,
        )  # fmt: skip
        society = Society(process, folder)
        threading.Thread(target=society.read, daemon=True).start()
        robots = ["Vacu", *(f"H{k}" for k in range(1, n))]
        row = [str(n), topology]
        try:
            up = _until(lambda: all(society.begun(r) for r in robots) and time.time(), limit)
            first = _until(lambda: _served(society, 0.0), limit)
            pids = list(society.pids().values())
            row.append(str(connections(pids)))
            row.append(f"{float(up) - began:.1f} s" if up else "-")  # type: ignore[arg-type]
            row.append(f"{float(first) - began:.1f} s" if first else "-")  # type: ignore[arg-type]
            cpu, sent, t0 = sum(_cpu(p) for p in pids), segments(), time.monotonic()
            time.sleep(idle)
            span = time.monotonic() - t0
            row.append(f"{100 * (sum(_cpu(p) for p in pids) - cpu) / span:.0f} %")
            row.append(f"{(segments() - sent) / span:.0f}")
            robot_pids = [p for r, p in society.pids().items() if r != "router"]
            rss = [_rss(p) for p in robot_pids]
            row.append(f"{max(rss) / 2**20:.0f} MB" if rss else "-")
            row.append(f"{sum(_rss(p) for p in pids) / 2**20:.0f} MB")
            row += _kill(society, limit) if first and n > 2 else ["-", "-"]  # 2: no other helper
        finally:
            os.killpg(process.pid, signal.SIGTERM)
            try:
                process.wait(60)
            except subprocess.TimeoutExpired:
                os.killpg(process.pid, signal.SIGKILL)
                process.wait(10)
        return row


def _kill(society: Society, limit: float) -> list[str]:
    """Kill the helper in use: the time to the switch and to goal data again."""
    start = next((r for r in society.trace("Vacu") if r.get("event") == "start"), {})
    given = start.get("partners", [])
    partners = [str(p) for p in given] if isinstance(given, list) else []
    helper = next((p for p in partners if p != "Vacu"), None)
    pid = society.pids().get(helper or "")
    if pid is None:
        return ["-", "-"]
    killed = time.time()
    os.kill(pid, signal.SIGKILL)

    def switched() -> float | None:
        for r in society.trace("Vacu"):
            if r.get("event") == "switch" and float(r["t"]) > killed:  # type: ignore[arg-type]
                return float(r["t"])  # type: ignore[arg-type]
        return None

    switch = _until(switched, limit)
    again = _until(lambda: _served(society, float(switch)) if switch else None, limit)  # type: ignore[arg-type]
    return [
        f"{1000 * (float(switch) - killed):.0f} ms" if switch else "-",  # type: ignore[arg-type]
        f"{1000 * (float(again) - killed):.0f} ms" if again else "-",  # type: ignore[arg-type]
    ]


HEADER = [
    "robots", "topology", "TCP connections", "all up", "goal data", "CPU (idle)",
    "TCP segments/s (idle)", "RSS per robot", "RSS total", "kill -> switch", "kill -> goal data",
]  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.scale", description=__doc__.split("\n")[0]
    )
    parser.add_argument(
        "--sizes", default="2,5,10,20", help="robots in the society (default 2,5,10,20)"
    )
    parser.add_argument("--topology", action="append", choices=TOPOLOGIES, help="default: both")
    parser.add_argument("--limit", type=float, default=240.0, help="seconds each wait may take")
    parser.add_argument("--idle", type=float, default=3.0, help="seconds of the idle window")
    args = parser.parse_args(argv)
    sizes = [int(s) for s in args.sizes.split(",")]
    load = os.getloadavg()[0]
    print(f"# cfgplan launch at scale: {platform.machine()}, {os.cpu_count()} cores, "
          f"Python {platform.python_version()}, load {load:.1f} at the start")  # fmt: skip
    print("| " + " | ".join(HEADER) + " |")
    print("|" + "---|" * len(HEADER))
    for n in sizes:
        for topology in args.topology or TOPOLOGIES:
            print("| " + " | ".join(measure(n, topology, args.limit, args.idle)) + " |", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
