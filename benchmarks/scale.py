"""The runtime at scale: ``python -m benchmarks.scale`` prints how a launched society grows.

``cfgplan launch`` of a generated docking society (domains/docking): Vacu,
whose laser failed, must dock, and each of N-1 helpers H1, H2, ... has a
laser that can tell Vacu its pose (any of them serves the goal). For each
size, and for the sizes of ``--mesh-sizes`` also in a mesh, side by side in
one run on this machine:

* *router* — launch's default: one Zenoh router (``cfgplan router``), every
  robot its client (``--router``);
* *router + keys* — the same with the society's keys (``--keys``, for the
  sizes of ``--keys-sizes``): the society's secured router, TLS with mutual
  authentication, access control enforced by the router and by each robot;
* *mesh* — ``--topology mesh``: every robot a peer linked to every other.

What each row measures is said by :data:`INTRO`; ``--markdown FILE`` also
writes the documentation's page (``docs/explanation/scale.md``). Before the
sweep, cfgplan's modules are compiled to bytecode (``compileall``, as ``pip
install`` does): a source checkout run with ``PYTHONDONTWRITEBYTECODE``
would compile every module again in every robot process.
"""

from __future__ import annotations

import argparse
import compileall
import json
import os
import re
import shlex
import signal
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from benchmarks.fault_conditions import DOCKING_IMPL
from benchmarks.page import revision
from benchmarks.reconfigure import table
from benchmarks.run import machine
from cfgplan.runtime.spawn import free_port

ROOT = Path(__file__).resolve().parents[1]
DOMAIN = ROOT / "domains" / "docking" / "domain.lisp"
KEYED = "router + keys"
TOPOLOGIES = ("router", KEYED, "mesh")
TICK = os.sysconf("SC_CLK_TCK")
PAGE = os.sysconf("SC_PAGE_SIZE")
BASE = 3
"""The size each row's switch is compared with: a switch among 50 robots
should take at most twice as long as among 3."""


@dataclass(frozen=True)
class Options:
    """Tuning of the benchmark."""

    limit: float = 240.0  # seconds any one wait may take
    idle: float = 3.0  # seconds of the idle window
    kills: int = 3  # helpers in use killed in a row, one after the other's switch
    between: float = 0.1  # seconds from the killed helpers being back to the next kill
    switch_limit: float = 30.0  # seconds a kill waits for its switch
    quiet: float = 0.5  # cores others may use before a row starts (waited for)
    settle: float = 20.0  # seconds a row waits for the machine to be that quiet
    reruns: int = 1  # a row during which others used more than ``quiet`` cores runs again
    rate: float = 10.0  # the robots' --rate


def state_text(n: int) -> str:
    """Vacu (no laser) and ``n`` - 1 helpers with lasers, all in the kitchen."""
    helpers = [f"H{k}" for k in range(1, n)]
    facts = ["(robot Vacu)", "(station Charger1)", "(in Vacu Kitchen)", "(in Charger1 Kitchen)"]
    for h in helpers:
        facts += [f"(robot {h})", f"(laser {h})", f"(in {h} Kitchen)"]
    return f"(state {' '.join(facts)})\n(goal (do-dock Vacu Charger1))\n"


# -- what the machine and the processes say ----------------------------------------


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


def busy() -> float:
    """Seconds of CPU the whole machine has spent busy (every core, /proc/stat)."""
    fields = Path("/proc/stat").read_text().split("\n", 1)[0].split()[1:]
    user, nice, system, _idle, _iowait, irq, softirq, steal = (int(f) for f in fields[:8])
    return (user + nice + system + irq + softirq + steal) / TICK


def _own() -> float:
    """Seconds of CPU this process has used (its polling is not the others')."""
    t = os.times()
    return t.user + t.system


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
    for name in ("/proc/net/tcp", "/proc/net/tcp6"):
        for line in Path(name).read_text().splitlines()[1:]:
            fields = line.split()
            if fields[3] == "01" and fields[9] in inodes:
                ends += 1
    return ends // 2


def segments(pids: set[int]) -> int:
    """TCP segments the sockets of these processes have sent (``ss``'s
    ``segs_out``): the society's own traffic, whatever else the machine sends."""
    out = subprocess.run(
        ["ss", "-tinpH"], capture_output=True, text=True, timeout=30, check=True
    ).stdout
    total, ours = 0, False
    for line in out.splitlines():
        if not line[:1].isspace():  # a socket's line: whose it is
            ours = any(int(pid) in pids for pid in re.findall(r"pid=(\d+)", line))
        elif ours:  # its TCP details
            sent = re.search(r"\bsegs_out:(\d+)", line)
            total += int(sent[1]) if sent else 0
    return total


def quiet(options: Options) -> tuple[float, float]:
    """Wait (at most ``options.settle`` s) until the machine's other work takes
    under ``options.quiet`` cores over a second; returns (cores then, seconds waited)."""
    started = time.monotonic()
    while True:
        b, own, t = busy(), _own(), time.monotonic()
        time.sleep(1.0)
        cores = (busy() - b - (_own() - own)) / (time.monotonic() - t)
        if cores < options.quiet or time.monotonic() - started > options.settle:
            return cores, time.monotonic() - started


# -- one launch ---------------------------------------------------------------------


@dataclass
class Society:
    """One launch, its output read as it comes."""

    process: subprocess.Popen[str]
    folder: Path
    lines: list[str] = field(default_factory=list)
    spent: float = 0.0  # CPU seconds of processes that were killed
    killed: list[tuple[str, int]] = field(default_factory=list)  # robot, lines said before

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

    def cpu(self) -> float:
        """CPU seconds of the launch and every process it started."""
        pids = [self.process.pid, *self.pids().values()]
        return self.spent + sum(_cpu(p) for p in pids)

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


def _until(found: Callable[[], object], limit: float, poll: float = 0.05) -> object | None:
    deadline = time.monotonic() + limit
    while time.monotonic() < deadline:
        got = found()
        if got:
            return got
        time.sleep(poll)
    return None


def _t(record: dict[str, object]) -> float:
    return float(record["t"])  # type: ignore[arg-type]


def _served(society: Society, after: float) -> float | None:
    """When Vacu's ``dock`` first ran on a pose after ``after`` (time.time())."""
    for r in society.trace("Vacu"):
        if (
            r.get("event") == "call"
            and r.get("functionality") == "dock"
            and r.get("status") == "ran"
            and _t(r) > after
        ):
            return _t(r)
    return None


def in_use(trace: list[dict[str, object]]) -> str | None:
    """The helper Vacu's configuration uses now: named by its last switch's
    started functionalities, else by its start's partners."""
    for r in reversed(trace):
        if r.get("event") == "switch":
            started = r.get("started")
            named = started.get("functionalities", []) if isinstance(started, dict) else []
            found = re.findall(r"\b(H\d+)\b", " ".join(str(f) for f in named))
            if found:
                return str(found[0])
        if r.get("event") == "start":
            partners = r.get("partners")
            given = [str(p) for p in partners] if isinstance(partners, list) else []
            return next((p for p in given if p != "Vacu"), None)
    return None


@dataclass
class Row:
    """What one launch measured; ``None``/empty: not seen within the limit."""

    n: int
    topology: str
    connections: int = 0
    up: float | None = None
    first: float | None = None
    idle_cpu: float = 0.0  # share of one core
    idle_segments: float = 0.0  # per second
    goal_messages: float = 0.0  # per second, what Vacu received
    rss_robot: float = 0.0  # median over the helpers, bytes
    rss_coordinator: float = 0.0  # Vacu's, bytes
    rss_total: float = 0.0  # the robots and the router
    switches: list[float] = field(default_factory=list)  # kill -> switch, seconds
    fallbacks: int = 0  # switches answered by a fallback planned ahead (else by a search)
    again: list[float] = field(default_factory=list)  # kill -> goal data
    seen: list[float] = field(default_factory=list)  # kill -> the coordinator's robot-lost
    load: tuple[float, float] = (0.0, 0.0)  # 1-min load average before, after
    others: float = 0.0  # cores the rest of the machine used during the row


def keys_for(folder: Path, robots: list[str]) -> Path:
    """The society's keys for ``robots`` (Vacu coordinates) and its router, in ``folder``."""
    from cfgplan.security.keys import make_society, plan_society, write_society

    plan = plan_society("scale", robots, (), robots[:1], ["router"])
    write_society(folder, make_society(plan), force=False)
    return folder


def measure(n: int, topology: str, options: Options) -> Row:
    """One row: ``n`` robots, ``topology`` (:data:`TOPOLOGIES`)."""
    row = Row(n, topology, load=(os.getloadavg()[0], 0.0))
    robots = ["Vacu", *(f"H{k}" for k in range(1, n))]
    with tempfile.TemporaryDirectory(prefix="cfgplan-scale-") as name:
        folder = Path(name)
        state, impl = folder / "state.lisp", folder / "impl.py"
        state.write_text(state_text(n))
        impl.write_text(DOCKING_IMPL)
        how = ["--topology", topology]
        if topology == KEYED:
            how = ["--topology", "router", "--keys", str(keys_for(folder / "keys", robots))]
        machine0, own0, began = busy(), _own(), time.time()
        process = subprocess.Popen(
            [sys.executable, "-m", "cfgplan", "launch", str(DOMAIN), str(state),
             "--impl", str(impl), *how,
             "--trace", str(folder / "run.jsonl"), "--rate", f"{options.rate:g}", "--respawn"],
            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, cwd=ROOT,
            start_new_session=True,
        )  # fmt: skip
        try:  # the launch's whole session is stopped below, whatever happens
            society = Society(process, folder)
            threading.Thread(target=society.read, daemon=True).start()
            everyone = lambda: all(society.begun(r) for r in robots) and time.time()  # noqa: E731
            up = _until(everyone, options.limit)
            row.up = float(up) - began if up else None  # type: ignore[arg-type]
            first = _until(lambda: _served(society, 0.0), options.limit)
            row.first = float(first) - began if first else None  # type: ignore[arg-type]
            pids = list(society.pids().values())
            row.connections = connections(pids)
            _idle(society, row, options)
            helpers = [p for r, p in society.pids().items() if r not in ("router", "Vacu")]
            row.rss_robot = statistics.median(_rss(p) for p in helpers) if helpers else 0
            row.rss_coordinator = _rss(society.pids().get("Vacu", 0))
            row.rss_total = sum(_rss(p) for p in society.pids().values())
            for _ in range(options.kills if first and n > 2 else 0):  # 2: no other helper
                if not _kill(society, row, options):
                    break
            ours = society.cpu()
        finally:
            os.killpg(process.pid, signal.SIGTERM)
            try:
                process.wait(60)
            except subprocess.TimeoutExpired:
                os.killpg(process.pid, signal.SIGKILL)
                process.wait(10)
        span = time.time() - began
        row.others = max(0.0, (busy() - machine0 - ours - (_own() - own0)) / span)
    row.load = (row.load[0], os.getloadavg()[0])
    return row


def _idle(society: Society, row: Row, options: Options) -> None:
    """The idle window: CPU of the society, TCP segments, Vacu's messages."""
    received = sum(1 for r in society.trace("Vacu") if r.get("event") == "receive")
    pids = set(society.pids().values())
    cpu, sent, t0 = society.cpu(), segments(pids), time.monotonic()
    time.sleep(options.idle)
    span = time.monotonic() - t0
    row.idle_cpu = (society.cpu() - cpu) / span
    row.idle_segments = (segments(pids) - sent) / span
    now = sum(1 for r in society.trace("Vacu") if r.get("event") == "receive")
    row.goal_messages = (now - received) / span


def _kill(society: Society, row: Row, options: Options) -> bool:
    """Kill (SIGKILL) the helper in use: the time to the switch and to goal
    data again; False when there was none to kill or nothing followed."""
    if _until(lambda: back(society), options.switch_limit, poll=0.002) is None:
        return False
    time.sleep(options.between)  # the fallbacks should be ready by now
    helper = in_use(society.trace("Vacu"))
    pid = society.pids().get(helper or "")
    if helper is None or pid is None:
        return False
    society.spent += _cpu(pid)
    society.killed.append((helper, len(society.lines)))
    killed = time.time()
    os.kill(pid, signal.SIGKILL)

    def switched() -> dict[str, object] | None:
        for r in society.trace("Vacu"):
            if r.get("event") == "switch" and _t(r) > killed:
                return r
        return None

    found = _until(switched, options.switch_limit)
    if not isinstance(found, dict):
        return False
    switch = _t(found)
    again = _until(lambda: _served(society, switch), options.switch_limit)
    if again is None:
        return False
    row.switches.append(switch - killed)
    row.fallbacks += found.get("source") == "fallback"
    lost = next(
        (
            _t(r)
            for r in society.trace("Vacu")
            if r.get("event") == "robot-lost" and r.get("other") == helper and _t(r) > killed
        ),
        None,
    )
    if lost is not None:
        row.seen.append(lost - killed)
    row.again.append(float(again) - killed)  # type: ignore[arg-type]
    return True


def back(society: Society) -> bool:
    """Whether Vacu has said that every helper killed so far works again
    (its ``recovery``, on its console, which says it at once: its trace is
    flushed once a cycle): respawned and past the hold, so that the next
    kill has the society's every helper to switch to, not one still coming
    back."""
    lines = society.lines
    return all(
        any(re.match(rf"Vacu +\| .*: {robot} works again \(", line) for line in lines[said:])
        for robot, said in society.killed
    )


# -- one robot process: the planner's or the emitted program --------------------------


@dataclass
class Program:
    """What one robot process takes as it starts: CPU to its first trace line, RSS."""

    name: str
    cpu: float = 0.0
    rss: float = 0.0


def programs(options: Options) -> list[Program]:
    """The society of 3's coordinator Vacu and helper H1, clients of a router,
    started as ``cfgplan run --robot``, and H1 as the program ``cfgplan emit
    --lang python`` writes (no planner); each alone, its CPU when its trace
    begins, its RSS a second later."""
    out: list[Program] = []
    with tempfile.TemporaryDirectory(prefix="cfgplan-scale-") as name:
        folder = Path(name)
        state, impl = folder / "state.lisp", folder / "impl.py"
        state.write_text(state_text(BASE))
        impl.write_text(DOCKING_IMPL)
        emitted = folder / "emitted"
        subprocess.run(
            [sys.executable, "-m", "cfgplan", "emit", str(DOMAIN), str(state), "--lang", "python",
             "-o", str(emitted)],
            check=True, capture_output=True, cwd=ROOT, timeout=options.limit,
        )  # fmt: skip
        port = free_port()
        router = subprocess.Popen(
            [sys.executable, "-m", "cfgplan", "router", "--listen", f"tcp/127.0.0.1:{port}"],
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, cwd=ROOT,
        )  # fmt: skip
        common = ["--impl", str(impl), "--router", f"tcp/127.0.0.1:{port}", "--society", "scale"]
        run = ["-m", "cfgplan", "run", str(DOMAIN), str(state), "--robot"]
        kinds = {
            "cfgplan run --robot Vacu (the coordinator: plans)": [*run, "Vacu"],
            "cfgplan run --robot H1 (a helper: plans nothing)": [*run, "H1"],
            "h1.py from cfgplan emit (no planner)": [str(emitted / "h1.py")],
        }
        try:
            for kind, args in kinds.items():
                trace = folder / f"{len(out)}.jsonl"
                process = subprocess.Popen(
                    [sys.executable, *args, *common, "--trace", str(trace)],
                    stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, cwd=ROOT,
                )  # fmt: skip
                try:
                    begun = _until(lambda t=trace: t.exists() and b"\n" in t.read_bytes(), 60)  # type: ignore[misc]
                    cpu = _cpu(process.pid) if begun else 0.0
                    time.sleep(1.0)
                    out.append(Program(kind, cpu, _rss(process.pid)))
                finally:
                    process.terminate()
                    process.wait(30)
        finally:
            router.terminate()
            router.wait(30)
    return out


# -- the tables and the page -----------------------------------------------------------

START_HEADER = [
    "robots", "topology", "TCP connections", "all up", "goal data", "CPU idle",
    "TCP segments/s idle", "goal messages/s", "RSS per helper", "RSS coordinator", "RSS total",
]  # fmt: skip
KILL_HEADER = [
    "robots", "topology", "kills", "by a fallback", "kill → loss seen", "kill → switch",
    "kill → goal data", f"switch ÷ {BASE} robots'", "load before / after", "others' CPU",
]  # fmt: skip
PROGRAM_HEADER = ["robot process", "CPU to its first trace line", "RSS"]


def _ms(values: list[float]) -> str:
    if not values:
        return "-"
    median = statistics.median(values)
    if len(values) == 1:
        return f"{1000 * median:.0f} ms"
    return f"{1000 * median:.0f} ms ({1000 * min(values):.0f}–{1000 * max(values):.0f})"


def _s(value: float | None) -> str:
    return f"{value:.1f} s" if value is not None else "-"


def start_cells(row: Row) -> list[str]:
    return [
        str(row.n), row.topology, str(row.connections), _s(row.up), _s(row.first),
        f"{100 * row.idle_cpu:.0f} %", f"{row.idle_segments:.0f}", f"{row.goal_messages:.0f}",
        f"{row.rss_robot / 2**20:.0f} MB", f"{row.rss_coordinator / 2**20:.0f} MB",
        f"{row.rss_total / 2**20:.0f} MB",
    ]  # fmt: skip


def kill_cells(row: Row, rows: list[Row]) -> list[str]:
    base = next((r for r in rows if r.n == BASE and r.topology == row.topology), None)
    ratio = "-"
    if base is not None and base.switches and row.switches:
        ratio = f"{statistics.median(row.switches) / statistics.median(base.switches):.1f}×"
    return [
        str(row.n), row.topology, str(len(row.switches)), str(row.fallbacks), _ms(row.seen),
        _ms(row.switches), _ms(row.again),
        ratio, f"{row.load[0]:.1f} / {row.load[1]:.1f}", f"{row.others:.2f} cores",
    ]  # fmt: skip


INTRO = """\
`python -m benchmarks.scale` starts a whole society with `cfgplan launch`
and watches it from outside. The society is generated: Vacu, whose laser
failed, must dock, and each of N−1 helpers H1, H2, … has a laser that can
tell Vacu its pose, so any of them serves the goal (domains/docking). Each
size runs in launch's default topology, *router* (one Zenoh router, every
robot its client: one connection each); some sizes also as *router + keys*
(`--keys`: the society's secured router, with its own certificate, every
link TLS with mutual authentication, the society's access control enforced
by the router on every robot and by every robot on the router), and the
small sizes also in a *mesh* (`--topology mesh`: every robot a peer linked
to every other), side by side in one run, at {rate:g} cycles per second.

Columns: the established TCP connections of the whole society (each counted
once); *all up*, every robot's trace begun, and *goal data*, Vacu's `dock`
running on a pose, after the launch started; over an idle window of
{idle:g} s, the CPU of every process of the society (100 % is one core),
the TCP segments the society's own sockets sent per second (`ss`'s
`segs_out`) and the messages Vacu's goal
received per second; the RSS of a robot process (the median) and of them
all with the router, the helpers' (the median) and the coordinator's apart.
Then the helper in use is killed (SIGKILL) {kills} times in a row, each once
the one killed before is back (launch's `--respawn` starts a killed helper
again, and the coordinator says it works again) and {between:g} s more:
that recovery switches nothing (the helper back costs what the running one
does), and the fallbacks of the situation it returns to must be ready by
then. Measured: how many switches a fallback planned ahead answered (*by a
fallback*; the others were planned by search), the time from the kill to the
coordinator's switch and to the goal's data again (median, min–max), the
first of them split off: the kill to the coordinator's `robot-lost` (Zenoh:
the router, or the peer, sees the connection close and withdraws the
robot's liveliness token), and the median switch over the same topology's
among {base} robots. The machine is shared: each row waits until other work takes
under {quiet:g} cores, records the load average before and after (the
society's own processes raise it), and the cores everything else used
while it ran (the machine's busy time less the society's and this
benchmark's); a row where that was above {quiet:g} ran again, and the run
with the least is shown. A `-` is what did not happen within {limit:g} s.

The robots are started together: with the router, launch picks one port
(the router's, bound to a free one), and the robots are its clients, so no
two can collide. Before the sweep cfgplan's modules are compiled to
bytecode, as `pip install` does; a source checkout run with
`PYTHONDONTWRITEBYTECODE=1` compiles every module again in every robot
process, which here costs a robot 0.2 s of CPU more at start.
"""

TARGETS = """\
## What the table says

{findings}

**Why a switch among many took longer, and what is left.** A switch after a
kill has two parts, and the table splits them: Zenoh's, the kill to the
coordinator's `robot-lost` ("kill → loss seen": the router sees the killed
robot's connection close and withdraws its liveliness tokens from the
clients that watch them), and cfgplan's, from that `robot-lost` to the
`switch` (the failure taken, the fallback planned ahead chosen, then the two
phases of the switch with the new helper: four messages through the
router). Timed hop by hop among 50 robots, the coordinator's own work took
under 2 ms and does not grow with N (a prepare and a commit go to the robots
whose part changes, not to all). What grew was everyone else's: every robot
watched every robot's liveliness, problem and planner tokens, so a kill was
news to all 49 processes at once; the router sent each the deletions, each woke its
loop while the coordinator switched, and on two cores the prepare and its
answer took 5 to 9 ms a hop in that burst instead of under 1 ms. A robot
that never coordinates now watches only the coordinator, the robots that
may take over, its partners and the coordinator it follows, and drops the
problem tokens once it met its own problem (the switch protocol,
[ready before anything is sent](switch-protocol.md#ready-before-anything-is-sent)):
a kill reaches the coordinator alone. What is left of the growth is the
busier machine: 50 idle robot loops and their keep-alives share the two
cores, so each wake-up on the way (the router's, the coordinator's, the new
helper's) waits longer for a core; on a loaded machine the spread between
kills is as wide as the difference between sizes.

**Fallbacks after a recovery.** Fallbacks are kept by situation, and a
recovery that switches nothing leaves the society in a situation whose
fallbacks for the running configuration were never computed (before the
kill it ran another helper). They were queued then, and at 50 robots each
takes tens of milliseconds to plan, so a kill within the next few hundred
milliseconds was planned by search. While a resource is out, the
coordinator now plans the situation its recovery returns to, and the
fallbacks there ([re-planning](monitoring.md#re-planning)): they are ready
before the helper is back, which the column *by a fallback* counts.

**Why all 50 take seconds to come up.** Started together, the robots share
the machine's cores: what each does before its trace begins is CPU, and that
CPU times N over the cores is the floor. Every robot used to plan its
configuration at start, to learn a part the coordinator sends it anyway:
0.32 s of CPU for a helper of this society of 50, 7 to 8 s of two cores for
all. A robot that never coordinates plans nothing now (the goal's method
runs `dock` on Vacu in every version, so Vacu coordinates, and no goal names
a helper, so none takes over): it reads and checks the domain and the state
(it announces its problem's fingerprint and must know the functionalities it
may be sent), opens its session and waits for its part, loading no search
(the [switch protocol](switch-protocol.md#who-decides)). Its CPU is imports,
most of them: typer, pydantic and the intermediate representation's models,
Lark, the checker, the runtime and Zenoh; reading, checking and compiling
the state of 50 robots takes 25 ms of it. Without bytecode on disk
(`PYTHONDONTWRITEBYTECODE` in a source checkout, as this machine's
environment sets) every robot compiles cfgplan again at start. The program
`cfgplan emit --lang python` writes for a robot imports only the runtime:

{programs}
"""

PAGE_TEXT = """\
<!-- Written by `{shown}`: do not edit by hand. -->

# The runtime at scale

{intro}
## The last run

{facts}

{start}

Kills of the helper in use, and the machine's load:

{kills}

{targets}
Made with `{shown}`; run it again to regenerate this page. The faults a
society rides out at its small size are on the [faults page](faults.md).
"""


def findings(rows: list[Row]) -> str:
    """What the run shows against the goals, from its own figures."""
    routed = sorted((r for r in rows if r.topology == "router"), key=lambda r: r.n)
    meshed = sorted((r for r in rows if r.topology == "mesh"), key=lambda r: r.n)
    keyed = sorted((r for r in rows if r.topology == KEYED), key=lambda r: r.n)
    out = []
    if routed:
        big = routed[-1]
        links = ", ".join(f"{r.connections} at {r.n}" for r in routed)
        out.append(f"- **Connections** through the router: {links} (one per robot).")
        if meshed:
            mesh = ", ".join(f"{r.connections} at {r.n}" for r in meshed)
            out.append(f"  In a mesh: {mesh} (launch asks for N·(N−1)/2; Zenoh may add more).")
        per = ", ".join(f"{r.idle_segments / r.n:.1f} at {r.n}" for r in routed)
        out.append(f"- **Idle traffic** per robot, TCP segments a second: {per}.")
        if meshed:
            per = ", ".join(f"{r.idle_segments / r.n:.1f} at {r.n}" for r in meshed)
            out.append(f"  In a mesh: {per}.")
        if big.switches:
            out.append(
                f"- **Fallbacks ready after a recovery**: among {big.n}, {big.fallbacks} of "
                f"{len(big.switches)} kills (each right after the helper killed before was "
                "back) were answered by a fallback planned ahead"
                + ("." if big.fallbacks == len(big.switches) else ", the others by a search.")
            )
        base = next((r for r in routed if r.n == BASE and r.switches), None)
        if base is not None and big.switches:
            ratio = statistics.median(big.switches) / statistics.median(base.switches)
            verdict = "within" if ratio <= 2.0 else "over"
            out.append(
                f"- **A switch among {big.n}** took {_ms(big.switches)}, {ratio:.1f}× the "
                f"{_ms(base.switches)} among {BASE}: {verdict} the goal of 2×."
            )
        if big.up is not None:
            verdict = "within" if big.up <= 10.0 else "over"
            out.append(
                f"- **All {big.n} up** after {big.up:.1f} s (started together): {verdict} the "
                f"goal of 10 s (other work on the machine took {big.others:.2f} cores "
                "during the row)."
            )
        out.append(
            f"- **Memory**: a helper's process holds {big.rss_robot / 2**20:.0f} MB, the "
            f"coordinator's {big.rss_coordinator / 2**20:.0f} MB (RSS; "
            f"{big.rss_total / 2**20:.0f} MB for all {big.n} and the router)."
        )
    if keyed:
        out.append(_keys_finding(keyed, routed))
    return "\n".join(out)


def _keys_finding(keyed: list[Row], routed: list[Row]) -> str:
    """What the society's keys cost behind the router, size by size."""
    plain = {r.n: r for r in routed}
    links = ", ".join(f"{r.connections} at {r.n}" for r in keyed)
    parts = [f"- **With keys**, through the secured router: connections {links}"]
    per = ", ".join(f"{r.idle_segments / r.n:.1f} at {r.n}" for r in keyed)
    parts.append(f"; idle TCP segments a second per robot {per}")
    pairs = [(r, plain[r.n]) for r in keyed if r.n in plain and r.switches and plain[r.n].switches]
    if pairs:
        said = ", ".join(
            f"{statistics.median(k.switches) / statistics.median(o.switches):.1f}× at {k.n}"
            for k, o in pairs
        )
        parts.append(f"; a switch took {said} the one without keys")
    ups = [(r, plain[r.n]) for r in keyed if r.n in plain and r.up and plain[r.n].up]
    if ups:
        said = ", ".join(f"{k.up:.1f} s against {o.up:.1f} s at {k.n}" for k, o in ups)
        parts.append(f"; all up after {said}")
    big = keyed[-1]
    base = next((r for r in keyed if r.n == BASE and r.switches), None)
    if base is not None and big.switches and big is not base:
        ratio = statistics.median(big.switches) / statistics.median(base.switches)
        parts.append(f"; a switch among {big.n} {ratio:.1f}× the one among {BASE}")
    return "".join(parts) + "."


def page(shown: str, options: Options, facts: str, tables: list[str], found: str) -> str:
    """The documentation page of a run: ``tables`` the start, kill and program tables."""
    intro = INTRO.format(
        rate=options.rate, idle=options.idle, kills=options.kills, base=BASE,
        between=options.between,
        quiet=options.quiet, limit=options.limit,
    )  # fmt: skip
    start, kills, program = tables
    targets = TARGETS.format(findings=found, programs=program)
    return PAGE_TEXT.format(
        shown=shown, intro=intro, facts=facts, start=start, kills=kills, targets=targets
    )


def rewrite(path: Path) -> None:
    """Write the page at ``path`` again with this module's words, its run's
    facts, tables and findings kept (nothing is measured)."""
    text = path.read_text(encoding="utf-8")
    made = re.search(r"^Made with `python -m benchmarks\.scale ?(.*?)`; run it again", text, re.M)
    run = text.split("## The last run\n", 1)
    if made is None or len(run) != 2:
        raise SystemExit(f"{path}: not a page benchmarks.scale wrote")
    blocks = [b.strip("\n") for b in run[1].split("\n\n")]
    facts = next(b for b in blocks if b.startswith("- machine:"))
    tables = [b.strip() for b in blocks if b.startswith("|")][:3]
    said = run[1].split("## What the table says\n\n", 1)[1].split("\n\n", 1)[0]
    args = parser().parse_args(shlex.split(made[1]))
    shown = shlex.join(["python", "-m", "benchmarks.scale", *shlex.split(made[1])])
    path.write_text(page(shown, options_of(args), facts, tables, said), encoding="utf-8")


def parser() -> argparse.ArgumentParser:
    """The command line of ``python -m benchmarks.scale``."""
    out = argparse.ArgumentParser(
        prog="python -m benchmarks.scale", description=__doc__.split("\n")[0]
    )
    out.add_argument(
        "--sizes", default="2,3,5,10,20,50", help="robots in the society (2,3,5,10,20,50)"
    )
    out.add_argument(
        "--keys-sizes",
        default="3,10,20,50",
        help="sizes also run with the society's keys, through its secured router (3,10,20,50)",
    )
    out.add_argument(
        "--mesh-sizes",
        default="2,3,5,10",
        help="sizes also run as a mesh (2,3,5,10; a mesh of 50 takes minutes to start)",
    )
    out.add_argument("--kills", type=int, default=3, help="helpers killed per row (3)")
    out.add_argument("--limit", type=float, default=240.0, help="seconds each wait may take")
    out.add_argument("--idle", type=float, default=3.0, help="seconds of the idle window")
    out.add_argument("--quiet", type=float, default=0.5, help="others' cores a row allows (0.5)")
    out.add_argument("--no-compile", action="store_true", help="do not compile cfgplan first")
    out.add_argument("--markdown", type=Path, help="also write the documentation page here")
    out.add_argument(
        "--rewrite", type=Path, metavar="PAGE", help="write PAGE again in this module's words"
    )
    return out


def options_of(args: argparse.Namespace) -> Options:
    return Options(limit=args.limit, idle=args.idle, kills=args.kills, quiet=args.quiet)


def main(argv: list[str] | None = None) -> int:
    args = parser().parse_args(argv)
    if args.rewrite:
        rewrite(args.rewrite)
        print(f"wrote {args.rewrite}")
        return 0
    # SIGTERM (a timeout) ends the run as Ctrl-C does: each launch is stopped by its finally
    signal.signal(signal.SIGTERM, lambda signum, frame: sys.exit(128 + signum))
    sizes = [int(s) for s in args.sizes.split(",")]
    meshes = {int(s) for s in args.mesh_sizes.split(",") if s}
    keyed = {int(s) for s in args.keys_sizes.split(",") if s}
    options = options_of(args)
    if not args.no_compile:
        compileall.compile_dir(ROOT / "cfgplan", quiet=1)
    started, load = time.monotonic(), os.getloadavg()[0]
    rows: list[Row] = []
    for n in sizes:
        for topology in TOPOLOGIES:
            if (topology == "mesh" and n not in meshes) or (topology == KEYED and n not in keyed):
                continue
            best: Row | None = None
            for _ in range(1 + options.reruns):
                quiet(options)
                got = measure(n, topology, options)
                best = got if best is None or got.others < best.others else best
                print(" | ".join(start_cells(got) + kill_cells(got, rows)[2:]), file=sys.stderr)
                if got.others <= options.quiet:
                    break
            assert best is not None
            rows.append(best)
    facts = [
        f"- machine: {machine()}",
        f"- date: {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}",
        f"- revision: `{revision()}`",
        f"- load average (1 min) at the start: {load:.2f}; "
        f"{time.monotonic() - started:.0f} s in all",
    ]
    start = table(START_HEADER, [start_cells(r) for r in rows])
    kills = table(KILL_HEADER, [kill_cells(r, rows) for r in rows])
    ran = programs(options)
    program = table(
        PROGRAM_HEADER, [[p.name, f"{p.cpu:.2f} s", f"{p.rss / 2**20:.0f} MB"] for p in ran]
    )
    print("\n\n".join(["\n".join(facts), start, kills, program, findings(rows)]))
    if args.markdown:
        given = sys.argv[1:] if argv is None else argv
        shown = shlex.join(["python", "-m", "benchmarks.scale", *given])
        text = page(shown, options, "\n".join(facts), [start, kills, program], findings(rows))
        args.markdown.write_text(text, encoding="utf-8")
        print(f"\nwrote {args.markdown}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
