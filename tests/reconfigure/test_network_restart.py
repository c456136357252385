"""A helper killed and started again rejoins its society (5.5).

Cross-door step 2 (6.2.2) with each robot its own process: Emil owns the goal
and coordinates, Pippi helps (both configurations need her). Pippi's process
is killed with SIGKILL and started again, twice: each time the society serves
the goal again with the new process, and no "silent" failure is recorded for
her. Before, the coordinator sent the restarted robot its part and the
prepare of the switch back as soon as her liveliness token appeared, before
her subscriber was known: the prepare was lost, the switch aborted after
2 s ("failure (silent)") and retried 1 s later, in most restarts. Hermetic:
loopback, free ports, scouting off, bounded waits, every process stopped by
its pid (:mod:`tests.runtime.netutil`).
"""

from __future__ import annotations

import os
import signal
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from tests.backends.support import EXAMPLE_IMPL
from tests.reconfigure.test_network import LIMIT, STEP2, _network, _robot
from tests.runtime.netutil import (
    Processes,
    Record,
    endpoint,
    free_port,
    processes,
    read_trace,
    wait_for,
)

SERVED = 30.0  # seconds: a process started on a loaded machine, and its first cycles


def _after(trace: Path, t: float, event: str, **fields: object) -> Callable[[], Record | None]:
    """A ``found`` for :func:`wait_for`: the first ``event`` of ``trace`` after ``t``
    with ``fields``."""

    def look() -> Record | None:
        for r in read_trace(trace):
            later = r["event"] == event and float(r["t"]) > t  # type: ignore[arg-type]
            if later and all(r.get(k) == v for k, v in fields.items()):
                return r
        return None

    return look


SERVED_FIELDS = {"functionality": "cross-door", "status": "ran"}
"""A trace event of the goal's action running on data (with ``call``)."""


def served_step2(running: Processes, folder: Path, society: str) -> tuple[Any, Path, list[str]]:
    """Emil (coordinating, 120 s at most) and Pippi of 6.2.2 step 2, each its
    own process, once the goal is served: Pippi's process, Emil's trace and
    Pippi's network options (``--listen P --connect E ...``)."""
    emil_net, pippi_net = _network(folder, society)
    _, emil_trace = _robot(running, folder, "Emil", EXAMPLE_IMPL, emil_net, "--duration", "120")
    pippi, _ = _robot(running, folder, "Pippi", EXAMPLE_IMPL, pippi_net)
    wait_for("the goal served", _after(emil_trace, 0.0, "call", **SERVED_FIELDS), LIMIT)
    return pippi, emil_trace, pippi_net


@pytest.mark.slow
def test_a_helper_killed_and_started_again_serves_the_goal_again(tmp_path: Path) -> None:
    served = SERVED_FIELDS
    with processes() as running:
        pippi, emil_trace, pippi_net = served_step2(running, tmp_path, "restart-test")
        for attempt in (1, 2):
            killed = time.time()
            os.kill(pippi.pid, signal.SIGKILL)  # type: ignore[attr-defined]
            assert pippi.wait(timeout=30) == -signal.SIGKILL  # type: ignore[attr-defined]
            wait_for("Pippi lost", _after(emil_trace, killed, "robot-lost"), LIMIT)
            folder = tmp_path / f"again-{attempt}"
            folder.mkdir()
            pippi, pippi_trace = _robot(running, folder, "Pippi", EXAMPLE_IMPL, pippi_net)
            started = wait_for("Pippi running again", _after(pippi_trace, 0.0, "start"), LIMIT)
            t = float(started["t"])  # type: ignore[arg-type]
            again = wait_for("the goal again", _after(emil_trace, t, "call", **served), SERVED)
            # with the restarted Pippi: she installed the configuration Emil switched to
            switch = wait_for("the switch back", _after(emil_trace, killed, "switch"), LIMIT)
            installs = [r["id"] for r in read_trace(pippi_trace) if r["event"] == "install"]
            assert switch["id"] in installs, (switch, installs)
            # a switch's round trip after her loop starts, not a lost prepare's 2 s and more
            assert float(again["t"]) - t < 2.0  # type: ignore[arg-type]
        running.stop_all()
    mine = read_trace(emil_trace)
    silent = [r for r in mine if r["event"] in ("failure", "abort") and "silent" in str(r)]
    assert silent == []
    assert [r["resource"] for r in mine if r["event"] == "failure"] == ["Pippi", "Pippi"]
    assert "Traceback" not in (tmp_path / "emil.log").read_text()


@pytest.mark.slow
def test_a_frozen_helper_back_next_to_its_replacement_is_told_it_is_a_duplicate(
    tmp_path: Path,
) -> None:
    """Found by a review: Pippi frozen past the lease, a new Pippi started in
    her place (the society takes it), then the frozen one let go. Both ran on,
    nothing said so, and when the new one was killed the old one's liveliness
    token (Zenoh shows two tokens of one key as one) hid the death: no
    ``robot Pippi lost``, only stale inputs 4 s later. Now the old process is
    told ``duplicate`` and ends (exit status 1, saying why), the society goes
    on with the new one, and the new one's death is seen at once."""
    with processes() as running:
        old, emil_trace, pippi_net = served_step2(running, tmp_path, "duplicate-test")
        time.sleep(1.0)  # past the first switches' hold
        stopped = time.time()
        os.kill(old.pid, signal.SIGSTOP)  # type: ignore[attr-defined]
        wait_for("Pippi lost", _after(emil_trace, stopped, "robot-lost"), LIMIT)
        folder = tmp_path / "new"
        folder.mkdir()
        elsewhere = [*pippi_net]  # the frozen one still holds its port
        elsewhere[elsewhere.index("--listen") + 1] = endpoint(free_port())
        new, new_trace = _robot(running, folder, "Pippi", EXAMPLE_IMPL, elsewhere)
        started = wait_for("the new Pippi runs", _after(new_trace, 0.0, "start"), LIMIT)
        t = float(started["t"])  # type: ignore[arg-type]
        wait_for("the goal, new Pippi", _after(emil_trace, t, "call", **SERVED_FIELDS), SERVED)
        let_go = time.time()
        os.kill(old.pid, signal.SIGCONT)  # type: ignore[attr-defined]
        assert old.wait(timeout=LIMIT) == 1  # type: ignore[attr-defined]
        said = (tmp_path / "pippi.log").read_text()
        assert "another process runs robot Pippi" in said or "duplicate" in said, said
        time.sleep(1.0)  # the society goes on with the new Pippi
        served = wait_for(
            "the goal after", _after(emil_trace, time.time(), "call", **SERVED_FIELDS), SERVED
        )
        assert new.poll() is None, "the new Pippi stopped"  # type: ignore[attr-defined]
        killed = time.time()
        os.kill(new.pid, signal.SIGKILL)  # type: ignore[attr-defined]
        lost = wait_for("the new Pippi lost", _after(emil_trace, killed, "robot-lost"), LIMIT)
        running.stop_all()
    assert float(served["t"]) > let_go  # type: ignore[arg-type]
    assert float(lost["t"]) - killed < 1.0, "the death was hidden"  # type: ignore[arg-type]
    errors = [r for r in read_trace(emil_trace) if r["event"] == "error"]
    assert any("a second process of robot Pippi" in str(r) for r in errors), errors


@pytest.mark.slow
def test_a_helper_stops_its_part_while_its_coordinator_is_gone(tmp_path: Path) -> None:
    """Measured: after ``kill -9`` of the coordinator a helper's action ran on
    at 20 Hz for 15 s, nobody watching. Now Pippi (``--without-coordinator``
    left at its default, stop) stops her part once Emil is gone for the hold
    (1 s): her console says so, her functionalities stop (no call after it).
    Emil started again (the same command) takes the society back: Pippi is
    sent her part, runs it, and his goal is served again."""
    emil_net, pippi_net = _network(tmp_path, "orphan-test")
    with processes() as running:
        emil, emil_trace = _robot(
            running, tmp_path, "Emil", EXAMPLE_IMPL, emil_net, "--duration", "120"
        )
        _pippi, pippi_trace = _robot(running, tmp_path, "Pippi", EXAMPLE_IMPL, pippi_net)
        wait_for("the goal served", _after(emil_trace, 0.0, "call", **SERVED_FIELDS), LIMIT)
        killed = time.time()
        os.kill(emil.pid, signal.SIGKILL)  # type: ignore[attr-defined]
        assert emil.wait(timeout=30) == -signal.SIGKILL  # type: ignore[attr-defined]

        def stopped() -> Record | None:
            found = _after(pippi_trace, killed, "error")()
            return found if found is not None and "stops its part" in str(found) else None

        said = wait_for("Pippi stops her part", stopped, LIMIT)
        at = float(said["t"])  # type: ignore[arg-type]
        time.sleep(2.0)
        calls = [
            r
            for r in read_trace(pippi_trace)
            if r["event"] == "call" and float(r["t"]) > at + 0.5  # type: ignore[arg-type]
        ]
        assert calls == [], calls[:3]
        folder = tmp_path / "again"
        folder.mkdir()
        _robot(running, folder, "Emil", EXAMPLE_IMPL, emil_net, "--duration", "60")
        again = time.time()
        wait_for(
            "the goal again",
            _after(folder / "emil.jsonl", 0.0, "call", **SERVED_FIELDS),
            LIMIT,
        )
        wait_for("Pippi runs again", _after(pippi_trace, again, "call", status="ran"), LIMIT)
        running.stop_all()
    assert at - killed < HOLD + 2.0, f"stopped {at - killed:.1f} s after the kill"
    assert "--without-coordinator stop" in (tmp_path / "pippi.log").read_text()


HOLD = 1.0  # cfgplan run's default hysteresis hold (--hold)


@pytest.mark.slow
def test_a_helper_restarted_with_an_edited_state_is_refused_alone(tmp_path: Path) -> None:
    """Measured (9 of 9): Pippi killed and started again with a state that
    differs by one fact nobody uses, ``(colour Pippi red)``: both the
    coordinator and the new process said "runs two problems ... both stop"
    and exited 1, and the run was over. Now the new process, which meets no
    robot of its problem, stops alone (exit 1), naming both problems; Emil
    is not taken in by it, runs on, and takes Pippi back when she is started
    again with the society's state."""
    with processes() as running:
        pippi, emil_trace, pippi_net = served_step2(running, tmp_path, "edited-test")
        killed = time.time()
        os.kill(pippi.pid, signal.SIGKILL)  # type: ignore[attr-defined]
        assert pippi.wait(timeout=30) == -signal.SIGKILL  # type: ignore[attr-defined]
        wait_for("Pippi lost", _after(emil_trace, killed, "robot-lost"), LIMIT)
        edited = tmp_path / "state-edited.lisp"
        original = Path(STEP2[1]).read_text()
        edited.write_text(original.replace("(robot Pippi)", "(robot Pippi) (colour Pippi red)", 1))
        assert edited.read_text() != original
        folder = tmp_path / "edited"
        folder.mkdir()
        args = ["-m", "cfgplan", "run", STEP2[0], str(edited), "--robot", "Pippi"]
        args += ["--impl", str(EXAMPLE_IMPL), "--rate", "20", *pippi_net]
        other = running.start(args, folder / "pippi.log")
        assert other.wait(timeout=LIMIT) == 1  # type: ignore[attr-defined]
        said = (folder / "pippi.log").read_text()
        assert "runs two problems" in said and "which met no robot of its own problem" in said
        assert "state-edited.lisp" in said and "state-6.2.2-step2.lisp" in said
        time.sleep(2.0)
        again = time.time()
        folder = tmp_path / "again"
        folder.mkdir()
        _robot(running, folder, "Pippi", EXAMPLE_IMPL, pippi_net)
        wait_for("the goal again", _after(emil_trace, again, "call", **SERVED_FIELDS), LIMIT)
        running.stop_all()
    mine = read_trace(emil_trace)
    assert [r for r in mine if r["event"] == "stop" and r.get("reason") == "refused"] == []
    errors = " ".join(str(r) for r in mine if r["event"] == "error")
    assert "announces another problem" in errors
