"""The coordinator of a sequence gone: the next robot takes over, and the old one follows it (5.5).

The 6.2.2 sequence, each robot its own process (``cfgplan run --robot``):
Pippi owns the first goal and coordinates, Emil helps her cross, then crosses
himself. The order of succession both derive from the goals is Pippi, Emil.

* Pippi killed while a switch of hers is in flight (the operator retracts
  Emil's compass, a scripted state update; Emil is frozen for less than the
  lease just before, so that the switch waits for his answer): Emil takes
  over within the lease and 1 s of running again — a run of the next
  generation, from the step the society was on — obeys nothing of the
  switch in flight, and stops safely (every configuration needs Pippi).
  Pippi started again steps down for him, and the sequence is served to its
  end under his coordination.
* Pippi frozen past the lease: Emil takes over the same way; let go, Pippi
  (the same process) steps down and follows him, and the sequence is served
  to its end.
* The successor killed in its turn, in its own step: the robot back takes
  over from it, and the successor started again follows.

Before, nobody took over: Emil ran on without a coordinator, and a Pippi
started again took the society back. Hermetic: loopback, free ports,
scouting off, bounded waits, every process stopped by its pid
(:mod:`tests.runtime.netutil`).
"""

from __future__ import annotations

import os
import signal
import time
from pathlib import Path
from typing import Any

import pytest

from cfgplan.runtime.schema import TRACE_EVENT
from cfgplan.security.keys import make_society, plan_society, write_society
from tests.reconfigure.test_network_restart import _after
from tests.reconfigure.test_sequence_network import SEQUENCE, STEPS
from tests.runtime.netutil import (
    Processes,
    Record,
    endpoint,
    free_port,
    hermetic_config,
    processes,
    read_trace,
    wait_for,
)

LIMIT = 90.0  # seconds: interpreters, a Zenoh handshake and crossings on a loaded machine
LEASE = 1.0
SERVED = {"functionality": "cross-door", "status": "ran"}
UPDATE = 60  # Pippi's cycle of the state update whose switch she dies in
NEXT = "next step: do-cross-door(Emil, Door1)"  # the cause of the switch to the last step


def _start(
    running: Processes, folder: Path, name: str, network: list[str]
) -> tuple[Any, Path, Path]:
    trace, log = folder / f"{name.lower()}.jsonl", folder / f"{name.lower()}.log"
    args = ["-m", "cfgplan", "run", *SEQUENCE, "--robot", name, "--impl", str(STEPS)]
    args += ["--rate", "20", "--duration", "120", "--trace", str(trace), *network]
    return running.start(args, log), trace, log


def _society(
    running: Processes,
    folder: Path,
    society: str,
    *extra: str,
    keyed: bool = False,
    emil: tuple[str, ...] = (),
) -> tuple[Any, Any, dict[str, list[str]]]:
    """Emil (helping, with ``emil``) and Pippi (coordinating, with ``extra``)
    once Pippi's crossing is served: both processes and each one's network
    options. ``keyed``: with the society's keys, both marked coordinators (as
    ``cfgplan keys new`` marks the robots the goals name)."""
    config = str(hermetic_config(folder))
    port = free_port()
    common = ["--zenoh-config", config, "--society", society, "--lease", f"{LEASE:g}"]
    if keyed:
        keys = folder / "keys"
        both = plan_society(society, ["Emil", "Pippi"], (), ["Pippi", "Emil"])
        write_society(keys, make_society(both), force=False)
        common += ["--keys", str(keys)]
    nets = {
        "Emil": ["--listen", endpoint(port), *common],
        "Pippi": ["--listen", endpoint(free_port()), "--connect", endpoint(port), *common],
    }
    emil, _, _ = _start(running, folder, "Emil", [*nets["Emil"], *emil])
    pippi, pippi_trace, _ = _start(running, folder, "Pippi", [*nets["Pippi"], *extra])
    wait_for("Pippi's crossing served", _after(pippi_trace, 0.0, "call", **SERVED), LIMIT)
    return emil, pippi, nets


def _events(trace: list[Record], *kinds: str, after: float = 0.0) -> list[Record]:
    return [r for r in trace if r["event"] in kinds and float(r["t"]) > after]  # type: ignore[arg-type]


def _taken_over_then_back(
    running: Processes,
    folder: Path,
    emil: Any,
    network: list[str],
    since: float,
    limit: float = LIMIT,
) -> tuple[Record, Path]:
    """Emil takes over after ``since`` (within ``limit`` seconds) and stops
    safely; Pippi, started again with ``network``, and he end the sequence:
    the takeover and her new trace."""
    emil_trace = folder / "emil.jsonl"
    takeover = wait_for("Emil takes over", _after(emil_trace, since, "takeover"), limit)
    t = float(takeover["t"])  # type: ignore[arg-type]
    wait_for("Emil stops safely", _after(emil_trace, t - 1e-6, "no-configuration"), 10.0)
    again = folder / "again"
    again.mkdir()
    back, again_trace, _ = _start(running, again, "Pippi", network)
    assert emil.wait(timeout=LIMIT) == 0
    assert back.wait(timeout=LIMIT) == 0
    return takeover, again_trace


def _served_to_the_end(folder: Path, again: Path, takeover: Record) -> None:
    """After the takeover, Emil coordinates the whole sequence again: Pippi
    (``again``: her trace since she is back) steps down and follows him, both
    crossings are accomplished and Emil ends the run, every robot told."""
    emil = read_trace(folder / "emil.jsonl")
    pippi = read_trace(again)
    t = float(takeover["t"])  # type: ignore[arg-type]
    (down,) = _events(pippi, "step-down")
    assert down["leader"] == "Emil" and down["epoch"] == takeover["epoch"]
    stepped = float(down["t"])  # type: ignore[arg-type]
    assert _events(pippi, "switch", after=stepped) == []
    # one coordinator's switches obeyed from then on, by both: Emil's run's
    installs = [*_events(emil, "install", after=t), *_events(pippi, "install", after=stepped)]
    obeyed = {str(r["epoch"]) for r in installs}
    assert obeyed == {takeover["epoch"]}, obeyed
    done = [r["event"] for r in _events(emil, "achieved", "finish", after=t)]
    assert done == ["achieved", "achieved", "finish"], done
    assert _events(emil, "finish")[-1]["silent"] == []
    (finish,) = _events(pippi, "finish")
    assert (finish["from"], finish["goal"]) == ("Emil", "do-cross-door(Emil, Door1)")
    for path in (folder / "emil.jsonl", again):
        for line in path.read_text(encoding="utf-8").splitlines():
            TRACE_EVENT.validate_json(line)


@pytest.mark.slow
def test_the_coordinator_killed_in_a_switch_is_taken_over_and_followed_when_back(
    tmp_path: Path,
) -> None:
    with processes() as running:
        update = f"retract (compass Emil) at cycle {UPDATE}"
        emil, pippi, nets = _society(running, tmp_path, "takeover-kill", "--inject", update)
        pippi_trace = tmp_path / "pippi.jsonl"

        def near() -> Record | None:  # 0.4 s before the update, at 20 cycles a second
            return next((r for r in read_trace(pippi_trace) if r["cycle"] >= UPDATE - 8), None)

        wait_for("Pippi near the update", near, LIMIT)
        stopped = time.time()
        os.kill(emil.pid, signal.SIGSTOP)  # type: ignore[attr-defined]
        # the update: Pippi prepares the switch to cameras (Emil's part too), which waits for him
        wait_for("Pippi's switch begins", _after(pippi_trace, stopped, "facts"), 10.0)
        os.kill(pippi.pid, signal.SIGKILL)  # type: ignore[attr-defined]
        assert pippi.wait(timeout=30) == -signal.SIGKILL  # type: ignore[attr-defined]
        os.kill(emil.pid, signal.SIGCONT)  # type: ignore[attr-defined]
        let_go = time.time()
        back = nets["Pippi"]
        takeover, again_trace = _taken_over_then_back(running, tmp_path, emil, back, let_go)
    t = float(takeover["t"])  # type: ignore[arg-type]
    assert (takeover["after"], takeover["step"]) == ("Pippi", 0)
    assert takeover["goal"] == "do-cross-door(Pippi, Door1)"
    assert str(takeover["epoch"]).startswith("2.")  # one generation after Pippi's first run
    assert t - let_go < LEASE + 1.0, t - let_go
    old = read_trace(pippi_trace)
    in_flight = _events(old, "facts", after=stopped)
    ended = [r["event"] for r in _events(old, "switch", "abort", "no-configuration", after=stopped)]
    assert in_flight and ended == [], (in_flight, ended)  # she died with the switch in flight
    emil = read_trace(tmp_path / "emil.jsonl")
    between = _events(emil, "install", after=stopped)
    assert [r for r in between if float(r["t"]) < t] == []  # type: ignore[arg-type]
    _served_to_the_end(tmp_path, again_trace, takeover)


@pytest.mark.slow
@pytest.mark.parametrize("keyed", [False, True], ids=["open", "keys"])
def test_the_coordinator_frozen_past_the_lease_is_taken_over_and_steps_down_when_let_go(
    tmp_path: Path, keyed: bool
) -> None:
    """With the society's keys too: the access control lets Emil, a
    coordinator, send switches and read the reports once he takes over."""
    with processes() as running:
        emil, pippi, _ = _society(running, tmp_path, "takeover-freeze", keyed=keyed)
        time.sleep(0.5)
        stopped = time.time()
        os.kill(pippi.pid, signal.SIGSTOP)  # type: ignore[attr-defined]
        emil_trace = tmp_path / "emil.jsonl"
        takeover = wait_for("Emil takes over", _after(emil_trace, stopped, "takeover"), LIMIT)
        time.sleep(max(0.0, stopped + 3 * LEASE - time.time()))
        os.kill(pippi.pid, signal.SIGCONT)  # type: ignore[attr-defined]
        assert emil.wait(timeout=LIMIT) == 0  # type: ignore[attr-defined]
        assert pippi.wait(timeout=LIMIT) == 0  # type: ignore[attr-defined]
    t = float(takeover["t"])  # type: ignore[arg-type]
    assert t - stopped < LEASE + 1.0, t - stopped
    assert (takeover["after"], takeover["step"]) == ("Pippi", 0)
    _served_to_the_end(tmp_path, tmp_path / "pippi.jsonl", takeover)


@pytest.mark.slow
def test_a_successor_killed_in_its_own_step_is_taken_over_by_the_robot_back(
    tmp_path: Path,
) -> None:
    """Pippi killed: Emil takes over (run 2); Pippi started again follows him
    and crosses. Emil, coordinating his own crossing (the last step, which
    names only him), is killed in turn: Pippi, whom the earlier goal names,
    takes over (run 3) and stops safely; Emil started again — no coordinator
    when he starts, for he does not own the first goal — follows her, and
    the sequence is served to its end under her coordination. Without
    someone to take over from the successor, both would wait for good."""
    with processes() as running:
        emil, pippi, nets = _society(running, tmp_path, "takeover-twice")
        emil_trace = tmp_path / "emil.jsonl"
        os.kill(pippi.pid, signal.SIGKILL)  # type: ignore[attr-defined]
        first = wait_for("Emil takes over", _after(emil_trace, 0.0, "takeover"), LIMIT)
        back = tmp_path / "pippi-back"
        back.mkdir()
        pippi, pippi_trace, _ = _start(running, back, "Pippi", nets["Pippi"])
        wait_for("Pippi follows", _after(pippi_trace, 0.0, "step-down"), LIMIT)
        step = wait_for("Emil's own step", _after(emil_trace, 0.0, "switch", cause=NEXT), LIMIT)
        os.kill(emil.pid, signal.SIGKILL)  # type: ignore[attr-defined]
        killed = time.time()
        second = wait_for("Pippi takes over", _after(pippi_trace, killed, "takeover"), LIMIT)
        wait_for("Pippi stops safely", _after(pippi_trace, killed, "no-configuration"), 10.0)
        again = tmp_path / "emil-back"
        again.mkdir()
        emil, emil_again, _ = _start(running, again, "Emil", nets["Emil"])
        assert pippi.wait(timeout=LIMIT) == 0  # type: ignore[attr-defined]
        assert emil.wait(timeout=LIMIT) == 0  # type: ignore[attr-defined]
    assert str(first["epoch"]).startswith("2.") and step["id"]
    assert (second["after"], second["step"]) == ("Emil", 1)
    assert second["goal"] == "do-cross-door(Emil, Door1)"
    assert str(second["epoch"]).startswith("3.")
    assert float(second["t"]) - killed < LEASE + 1.0  # type: ignore[arg-type]
    hers = read_trace(pippi_trace)
    after = float(second["t"])  # type: ignore[arg-type]
    done = [r["event"] for r in _events(hers, "achieved", "finish", after=after)]
    assert done == ["achieved", "finish"], done
    his = read_trace(emil_again)
    assert {str(r["epoch"]) for r in _events(his, "install")} == {second["epoch"]}
    (finish,) = _events(his, "finish")
    assert (finish["from"], finish["goal"]) == ("Pippi", "do-cross-door(Emil, Door1)")
