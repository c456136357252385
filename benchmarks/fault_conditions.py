"""The conditions of the fault benchmark, each one trial against real processes (5.5).

A trial starts one ``cfgplan run --robot`` process per robot over Zenoh —
across the lossy link of :mod:`benchmarks.lossy_link` — waits until the
goal's action runs, applies one condition to the helper or the link (kill -9
and a restart, SIGSTOP/SIGCONT, packet loss, a cut, a delay), watches until
the action runs on fresh data again or ``watch`` seconds pass after the
condition cleared, stops every process by its pid, and measures from the
coordinator's trace (``t`` is wall-clock time, as ``time.time()`` here):

* *detection* — the fault to the coordinator's first ``failure``,
  ``robot-lost`` or ``stale`` event;
* *switch* — the fault to its first ``switch`` or ``no-configuration``;
* *recovery* — the condition cleared to the goal's first call with status
  ``ran`` (inputs fresh) after it; none within ``watch``: a permanent stop.
  A kill clears when the restarted process's trace says ``start``;
* *spurious* — ``switch`` and ``no-configuration`` events from the fault on,
  counted for the light rows (≤ 10 % loss, the delay);
* *served* — the goal's ``ran`` calls while the fault lasted over the cycles
  the rate allows in that time.
"""

from __future__ import annotations

import contextlib
import json
import os
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Literal

from benchmarks.lossy_link import Link, NetnsLink, ProxyLink
from benchmarks.reconfigure import DOMAINS, HERMETIC, IMPL, ROOT
from cfgplan.runtime.spawn import free_port
from cfgplan.runtime.zenoh_config import DEFAULT_LEASE

Record = dict[str, object]
Kind = Literal["kill", "freeze", "loss", "cut"]


@dataclass(frozen=True)
class Options:
    """Tuning of the benchmark."""

    trials: int = 3
    loss_seconds: float = 30.0  # how long a loss or delay row lasts
    watch: float = 20.0  # seconds after the fault clears before a run counts as stopped for good
    hold: float = 1.0  # cfgplan run's hysteresis hold (--hold), for the limit hold + 1 s
    rate: float = 20.0  # cycles per second (--rate)
    lease: float = DEFAULT_LEASE  # --lease: cfgplan's default
    restart_after: float = 2.0  # a killed robot is started again after this
    settle: float = 1.5  # seconds of service before the fault (past the first switches' hold)
    startup: float = 90.0  # bound on the first service: interpreters and Zenoh, loaded machine
    seed: int = 33  # the link's dropped packets


@dataclass(frozen=True)
class Scenario:
    """A society: the coordinator owns the goal, the helper is faulted."""

    name: str
    domain: Path
    state: Path
    coordinator: str
    helper: str
    goal: str  # the goal's action (functionality name)
    impl: str = ""  # source of the implementations; empty: examples/cross-door/impl.py
    state_text: str = ""  # a state written for the trial instead of ``state``


CROSS_DOOR = Scenario(
    "cross-door 6.2.2 step 2",
    DOMAINS / "cross-door/domain.lisp",
    DOMAINS / "cross-door/state-6.2.2-step2.lisp",
    "Emil",
    "Pippi",
    "cross-door",
)

DOCKING_IMPL = '''\
"""Docking (domains/docking), for the fault benchmark: fixed readings."""
from cfgplan.runtime import current_robot, functionality

@functionality("laser")
def laser() -> dict[str, object]:
    return {"by": current_robot(), "ranges": [1.0, 1.5, 2.0]}

@functionality("camera")
def camera() -> dict[str, object]:
    return {"by": current_robot(), "pixels": [0, 1, 0]}

@functionality("scan-match")
def scan_match(robot: str, scan: object) -> list[float]:
    return [1.0, 2.0, 0.5]

@functionality("track")
def track(robot: str, image: object) -> list[float]:
    return [1.0, 2.0, 0.5]

@functionality("dock")
def dock(station: str, pose: object) -> None:
    return None
'''

DOCKING = Scenario(
    "docking, Vacu's laser failed: Robby helps; CamKitchen declared, its process not started",
    DOMAINS / "docking/domain.lisp",
    DOMAINS / "docking/state-kitchen-laser-failed.lisp",
    "Vacu",
    "Robby",
    "dock",
    DOCKING_IMPL,
)

DOCKING_ALONE = replace(
    DOCKING,
    name="docking, Vacu's laser failed, no camera: only Robby can help",
    state_text=(
        "(state (robot Vacu) (robot Robby) (laser Robby) (station Charger1)\n"
        "       (in Vacu Kitchen) (in Robby Kitchen) (in Charger1 Kitchen))\n"
        "(goal (do-dock Vacu Charger1))\n"
    ),
)


@dataclass(frozen=True)
class Condition:
    """One row: ``seconds`` of a freeze or a cut (a loss: Options.loss_seconds)."""

    name: str
    kind: Kind
    seconds: float = 0.0
    loss: float = 0.0
    delay: float = 0.0
    light: bool = False  # a switch or a stop under it is spurious
    scenario: Scenario = CROSS_DOOR


CONDITIONS = [
    Condition("kill -9 Pippi, restarted after 2 s", "kill"),
    Condition("Pippi frozen 0.8 s", "freeze", seconds=0.8),
    Condition("Pippi frozen 5 s", "freeze", seconds=5.0),
    Condition("10 % loss", "loss", loss=0.10, light=True),
    Condition("20 % loss", "loss", loss=0.20),
    Condition("50 % loss", "loss", loss=0.50),
    Condition("link cut 5 s", "cut", seconds=5.0),
    Condition("100 ms delay + 5 % loss", "loss", loss=0.05, delay=0.1, light=True),
    Condition("docking: kill -9 Robby, restarted (no camera)", "kill", scenario=DOCKING_ALONE),
    Condition(
        "docking: kill -9 Robby, restarted (camera declared, not running)",
        "kill",
        scenario=DOCKING,
    ),
]


@dataclass
class Trial:
    """What one trial measured (seconds; None: not seen)."""

    detection: float | None = None
    switch: float | None = None
    recovery: float | None = None
    spurious: int = 0
    served: float | None = None
    events: list[tuple[float, str]] = field(default_factory=list)  # the coordinator's: (s, what)
    cleared: float = 0.0  # seconds from the fault to its clearing
    error: str = ""


class TrialError(RuntimeError):
    """A trial that could not be run (the society never served its goal first)."""


def read_trace(path: Path) -> list[Record]:
    """The complete lines of a trace that may still be growing."""
    if not path.exists():
        return []
    lines = path.read_text(encoding="utf-8", errors="replace").split("\n")[:-1]
    out = []
    for line in lines:
        with contextlib.suppress(json.JSONDecodeError):
            out.append(json.loads(line))
    return out


def _t(record: Record) -> float:
    return float(record["t"])  # type: ignore[arg-type]


def wait_for(what: str, found: Callable[[], Record | None], limit: float) -> Record | None:
    """Poll ``found`` until it returns a record or ``limit`` seconds pass."""
    deadline = time.monotonic() + limit
    while time.monotonic() < deadline:
        got = found()
        if got is not None:
            return got
        time.sleep(0.02)
    return None


def _after(trace: Path, t: float, event: str, **fields: object) -> Callable[[], Record | None]:
    def look() -> Record | None:
        for r in read_trace(trace):
            if r["event"] == event and _t(r) > t and all(r.get(k) == v for k, v in fields.items()):
                return r
        return None

    return look


class Society:
    """The processes of one trial: the coordinator on side 0 of the link, the
    helper on side 1; each stopped by its pid."""

    def __init__(self, scenario: Scenario, link: Link, folder: Path, options: Options) -> None:
        self.scenario, self.link, self.folder, self.options = scenario, link, folder, options
        self.processes: list[subprocess.Popen[bytes]] = []
        config = folder / "hermetic.json5"
        config.write_text(HERMETIC)
        impl = folder / "impl.py"
        if scenario.impl:
            impl.write_text(scenario.impl)
        self.impl = str(impl) if scenario.impl else str(IMPL)
        self.state = scenario.state
        if scenario.state_text:
            self.state = folder / "state.lisp"
            self.state.write_text(scenario.state_text)
        common = ["--zenoh-config", str(config), "--society", f"faults-{folder.name}"]
        common += ["--lease", f"{options.lease:g}", "--hold", f"{options.hold:g}"]
        if isinstance(link, NetnsLink):
            coordinator, helper = (f"tcp/{a}:7447" for a in link.addresses)
            self.network = (
                ["--listen", coordinator, *common],
                ["--listen", helper, "--connect", coordinator, *common],
            )
        else:
            assert isinstance(link, ProxyLink)
            self.network = (
                ["--listen", f"tcp/127.0.0.1:{link.target}", *common],
                [
                    *("--listen", f"tcp/127.0.0.1:{free_port()}"),
                    *("--connect", f"tcp/127.0.0.1:{link.port}", *common),
                ],
            )

    def start(self, side: int, tag: str, *extra: str) -> tuple[subprocess.Popen[bytes], Path]:
        """Start the coordinator (side 0) or the helper (1); ``tag`` names its files."""
        robot = (self.scenario.coordinator, self.scenario.helper)[side]
        trace = self.folder / f"{tag}.jsonl"
        command = [sys.executable, "-m", "cfgplan", "run", str(self.scenario.domain)]
        command += [str(self.state), "--robot", robot, "--impl", self.impl]
        command += ["--rate", f"{self.options.rate:g}", "--trace", str(trace)]
        command += [*self.network[side], *extra]
        if isinstance(self.link, NetnsLink):
            command = self.link.wrap(side, command)
        with open(self.folder / f"{tag}.log", "wb") as log:
            process = subprocess.Popen(
                command, cwd=ROOT, stdout=log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL
            )
        self.processes.append(process)
        return process, trace

    def stop(self) -> None:
        for process in self.processes:
            if process.poll() is None:
                with contextlib.suppress(ProcessLookupError):
                    os.kill(process.pid, signal.SIGCONT)
                    os.kill(process.pid, signal.SIGTERM)
        for process in self.processes:
            try:
                process.wait(10)
            except subprocess.TimeoutExpired:
                with contextlib.suppress(ProcessLookupError):
                    os.kill(process.pid, signal.SIGKILL)
                process.wait(10)


def run_trial(condition: Condition, options: Options, link: Link, folder: Path) -> Trial:
    """One trial of ``condition`` (see the module's docstring)."""
    scenario, o = condition.scenario, options
    goal = {"functionality": scenario.goal, "status": "ran"}
    society = Society(scenario, link, folder, o)
    bound = o.startup + o.settle + o.loss_seconds + o.restart_after + 60 + 2 * o.watch
    try:
        _, trace = society.start(0, "coordinator", "--duration", f"{bound:g}")
        helper, _ = society.start(1, "helper")
        if wait_for("the goal served", _after(trace, 0.0, "call", **goal), o.startup) is None:
            raise TrialError(f"{scenario.goal} never ran within {o.startup:g} s of the start")
        time.sleep(o.settle)
        fault = time.time()
        cleared = _apply(condition, o, society, helper, link)
        if cleared is None:
            raise TrialError("the restarted helper never started")
        wait_for("the goal again", _after(trace, cleared, "call", **goal), o.watch)
    finally:
        society.stop()
        link.set(0.0, 0.0)
    return measure(read_trace(trace), condition, o, fault, cleared)


def _apply(
    condition: Condition,
    o: Options,
    society: Society,
    helper: subprocess.Popen[bytes],
    link: Link,
) -> float | None:
    """Apply the condition now; returns when it cleared (time.time())."""
    if condition.kind == "kill":
        start = time.monotonic()
        os.kill(helper.pid, signal.SIGKILL)
        helper.wait(30)
        time.sleep(max(0.0, start + o.restart_after - time.monotonic()))
        _, trace = society.start(1, "helper-again")
        started = wait_for("the helper again", _after(trace, 0.0, "start"), o.startup)
        return None if started is None else _t(started)
    if condition.kind == "freeze":
        os.kill(helper.pid, signal.SIGSTOP)
        time.sleep(condition.seconds)
        os.kill(helper.pid, signal.SIGCONT)
        return time.time()
    seconds = condition.seconds if condition.kind == "cut" else o.loss_seconds
    link.set(1.0 if condition.kind == "cut" else condition.loss, condition.delay)
    time.sleep(seconds)
    link.set(0.0, 0.0)
    return time.time()


ADAPTATION = (
    *("failure", "recovery", "switch", "no-configuration", "abort"),
    *("robot-lost", "robot-seen", "error"),
)


def _describe(r: Record) -> str:
    what = str(r["event"])
    for key in ("resource", "how", "other", "from_cost", "to_cost", "cause", "reason"):
        if key in r:
            what += f" {key}={r[key]}"
    return what


def measure(
    trace: list[Record], condition: Condition, o: Options, fault: float, cleared: float
) -> Trial:
    """The figures of one trial from the coordinator's trace."""
    after = [r for r in trace if _t(r) >= fault]
    goal = [
        r for r in after if r["event"] == "call" and r["functionality"] == condition.scenario.goal
    ]

    def first(*kinds: str) -> float | None:
        found = next((r for r in after if r["event"] in kinds), None)
        return None if found is None else _t(found) - fault

    again = next((r for r in goal if r["status"] == "ran" and _t(r) > cleared), None)
    recovery = None if again is None or _t(again) - cleared > o.watch else _t(again) - cleared
    during = [r for r in goal if r["status"] == "ran" and _t(r) < cleared]
    cycles = max(1.0, (cleared - fault) * o.rate)
    switches = [r for r in after if r["event"] in ("switch", "no-configuration")]
    return Trial(
        detection=first("failure", "robot-lost", "stale"),
        switch=first("switch", "no-configuration"),
        recovery=recovery,
        spurious=len(switches) if condition.light else 0,
        served=min(1.0, len(during) / cycles),
        events=[(_t(r) - fault, _describe(r)) for r in after if r["event"] in ADAPTATION],
        cleared=cleared - fault,
    )
