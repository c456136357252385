"""A helper frozen and let go: the society serves its goal again by itself (5.5, issue 33).

Cross-door step 2 (6.2.2), each robot its own process: Emil owns the goal and
coordinates, Pippi helps (every configuration needs her). Pippi is frozen
(SIGSTOP) for 0.8 s — about the 1 s lease, with the silence before the
freeze: she may be lost or only her data stop — and for 5 s — she is
lost — then let go (SIGCONT). Each time the goal's action
runs on fresh data again within hold + 1 s of her running again, by itself
(no scripted ``recover``), and the coordinator's own robot is never taken as
failed. Before, Pippi woke up seeing Emil lost (her lease of him ran out
while she was stopped), the coordinator believed her, withdrew its own facts
and stopped for good. Hermetic: loopback, free ports, scouting off, bounded
waits, every process stopped by its pid (:mod:`tests.runtime.netutil`).
"""

from __future__ import annotations

import os
import signal
import time
from pathlib import Path

import pytest

from tests.reconfigure.test_network import LIMIT
from tests.reconfigure.test_network_restart import SERVED_FIELDS, _after, served_step2
from tests.runtime.netutil import processes, read_trace, wait_for

HOLD = 1.0  # cfgplan run's default hysteresis hold (--hold)


@pytest.mark.slow
@pytest.mark.parametrize("frozen", [0.8, 5.0])
def test_a_helper_frozen_and_let_go_serves_the_goal_again(tmp_path: Path, frozen: float) -> None:
    served = SERVED_FIELDS
    with processes() as running:
        pippi, emil_trace, _ = served_step2(running, tmp_path, "freeze-test")
        time.sleep(1.0)  # past the first switches' hold
        stopped = time.time()
        os.kill(pippi.pid, signal.SIGSTOP)  # type: ignore[attr-defined]
        wait_for("the goal's data stops", _after(emil_trace, stopped, "failure"), LIMIT)
        time.sleep(max(0.0, stopped + frozen - time.time()))
        os.kill(pippi.pid, signal.SIGCONT)  # type: ignore[attr-defined]
        let_go = time.time()
        again = wait_for("the goal again", _after(emil_trace, let_go, "call", **served), LIMIT)
        running.stop_all()
    assert float(again["t"]) - let_go < HOLD + 1.0  # type: ignore[arg-type]
    mine = read_trace(emil_trace)
    failed = [r["resource"] for r in mine if r["event"] == "failure"]
    assert "Emil" not in failed, failed  # Pippi's view of Emil after her freeze
    if frozen > 1.0:  # past the lease: lost (0.8 s may be, with the silence before it)
        assert "Pippi" in failed, failed
