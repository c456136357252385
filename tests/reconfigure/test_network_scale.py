"""A society of 50 robots over Zenoh: a failure right after a recovery is answered by a
fallback planned ahead (5.5, 7.2).

``cfgplan launch --respawn`` of the generated docking society of
``benchmarks.scale`` (Vacu must dock, 49 helpers can each lend it a laser).
The helper in use is killed: Vacu switches to another; the killed one is
started again and recovers, which switches nothing (its configuration costs
what the running one does). At once, the helper in use is killed again: the
fallback for that loss in the situation the recovery returned to must be
known already. Before, the recovery queued those fallbacks anew, and at 50
robots each took tens of milliseconds to plan, so a failure within the next
~0.1-0.3 s was planned by search (``source: search`` in its switch); they
are now planned while the helper was out (``Reconfigurator.look_ahead``).
How soon after a recovery they are ready is measured by ``python -m
benchmarks.scale`` (its kills come 0.1 s after the recovery), not timed
here. Hermetic: loopback, the router on a free port, scouting off, every
wait bounded, the launch (which stops every robot by its pid) stopped by
its pid and every robot's pid checked gone.
"""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path

import pytest

from benchmarks.fault_conditions import DOCKING_IMPL
from benchmarks.scale import DOMAIN, Society, in_use, state_text
from tests.backends.support import ROOT
from tests.cli.test_launch import _gone
from tests.runtime.netutil import Record, wait_for

ROBOTS = 50
START = 300.0  # seconds: 50 interpreters and Zenoh sessions on a loaded machine of 2 cores
LIMIT = 60.0  # seconds any other wait may take


def _said(society: Society, pattern: str) -> Callable[[], Record | None]:
    """Whether the launch's output has a line matching ``pattern`` yet (the
    console says each event at once; the trace is flushed once a cycle)."""
    lines = society.lines
    return lambda: next(({"line": ln} for ln in list(lines) if re.search(pattern, ln)), None)


def _traced(society: Society, since: float, **fields: object) -> Callable[[], Record | None]:
    """Vacu's first trace record after ``since`` (time.time()) with ``fields``."""

    def found() -> Record | None:
        for r in society.trace("Vacu"):
            if float(r["t"]) > since and all(r.get(k) == v for k, v in fields.items()):  # type: ignore[arg-type]
                return r
        return None

    return found


@pytest.mark.slow
def test_a_failure_right_after_a_recovery_among_50_robots_is_answered_by_a_fallback(
    tmp_path: Path,
) -> None:
    state, impl = tmp_path / "state.lisp", tmp_path / "impl.py"
    state.write_text(state_text(ROBOTS), encoding="utf-8")
    impl.write_text(DOCKING_IMPL, encoding="utf-8")
    launched = subprocess.Popen(
        [sys.executable, "-m", "cfgplan", "launch", str(DOMAIN), str(state), "--impl", str(impl),
         "--trace", str(tmp_path / "run.jsonl"), "--rate", "10", "--respawn"],
        cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
    )  # fmt: skip
    society = Society(launched, tmp_path)
    threading.Thread(target=society.read, daemon=True).start()
    try:
        served = _traced(society, 0.0, event="call", functionality="dock", status="ran")
        wait_for("Vacu docks on a helper's pose", served, START)
        first = in_use(society.trace("Vacu"))
        assert first is not None
        killed = time.time()
        os.kill(society.pids()[first], signal.SIGKILL)
        switched = _traced(society, killed, event="switch")
        wait_for(f"a switch after {first} is killed", switched, LIMIT)
        second = in_use(society.trace("Vacu"))
        assert second is not None and second != first
        back = rf"^Vacu +\| .*: {first} works again \("
        wait_for(f"{first} started again and back", _said(society, back), LIMIT, poll=0.005)
        again = time.time()
        os.kill(society.pids()[second], signal.SIGKILL)  # at once: within milliseconds
        lost = _traced(society, again, event="switch")
        answer = wait_for(f"a switch after {second} is killed", lost, LIMIT)
        switches = [r for r in society.trace("Vacu") if r["event"] == "switch"]
    finally:
        launched.send_signal(signal.SIGTERM)
        try:
            launched.wait(LIMIT)
        except subprocess.TimeoutExpired:
            launched.kill()
            launched.wait(LIMIT)
    assert [r["cause"] for r in switches] == [f"{first} failed", f"{second} failed"]  # no other
    assert answer["source"] == "fallback", answer
    started = answer["started"]
    assert isinstance(started, dict)
    assert any(f"({first}" in str(f) for f in started["functionalities"]), started
    assert all(_gone(pid) for pid in society.pids().values())
