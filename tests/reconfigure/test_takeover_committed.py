"""A successor plans from what the society committed, not from its state file (5.5, 7.2).

The 6.2.2 sequence, each robot its own process: Pippi coordinates, Emil
helps her cross. The operator retracts ``(compass Emil)`` on Pippi's side
(a scripted state update, which only the coordinator applies): the society
switches from the compasses (44) to the cameras (47), and Pippi tells every
robot what it committed. Pippi is then killed: Emil takes over, and plans
from what the society committed — without Emil's compass — not from the
state file he was started with. Pippi started again steps down for him, and
both crossings are served on the cameras (47 each), under his run, to the
end.

Before, the successor knew only its state file: the retraction was lost with
Pippi, and Emil planned the compasses again (44), which the operator had
said were not there. Hermetic: loopback, free ports, scouting off, bounded
waits, every process stopped by its pid (:mod:`tests.runtime.netutil`).
"""

from __future__ import annotations

import json
import os
import signal
import time
from pathlib import Path

import pytest

from tests.reconfigure.test_network_restart import _after
from tests.reconfigure.test_network_takeover import (
    LEASE,
    LIMIT,
    SERVED,
    _events,
    _served_to_the_end,
    _society,
    _taken_over_then_back,
)
from tests.runtime.netutil import processes, read_trace, wait_for

UPDATE = 60  # Pippi's cycle of the operator's retraction (her crossing runs then)
RETRACTED = "(compass Emil)"


@pytest.mark.slow
def test_a_successor_plans_from_the_state_update_the_society_committed(tmp_path: Path) -> None:
    with processes() as running:
        update = f"retract {RETRACTED} at cycle {UPDATE}"
        emil, pippi, nets = _society(running, tmp_path, "takeover-state", "--inject", update)
        pippi_trace, emil_trace = tmp_path / "pippi.jsonl", tmp_path / "emil.jsonl"
        switched = wait_for(
            "Pippi's switch for the update",
            _after(pippi_trace, 0.0, "switch", cause="state update"),
            LIMIT,
        )
        wait_for("Emil installs it", _after(emil_trace, 0.0, "install", id=switched["id"]), 10.0)
        time.sleep(0.3)  # a few of Pippi's cycles: she tells what she committed in the next
        os.kill(pippi.pid, signal.SIGKILL)  # type: ignore[attr-defined]
        killed = time.time()
        back = nets["Pippi"]
        takeover, again_trace = _taken_over_then_back(running, tmp_path, emil, back, killed)
    t = float(takeover["t"])  # type: ignore[arg-type]
    assert (switched["from_cost"], switched["to_cost"]) == (44, 47)
    assert (takeover["after"], takeover["step"]) == ("Pippi", 0)
    assert str(takeover["epoch"]).startswith("2.")
    assert t - killed < LEASE + 1.0, t - killed
    # After the fault: both crossings on the cameras, under Emil's run, to the end.
    emil_after = _events(read_trace(emil_trace), "switch", after=t)
    assert [r["to_cost"] for r in emil_after] == [47, 47], emil_after
    for switch in emil_after:
        running = json.dumps([switch["kept"], switch["started"]])
        assert "compass(Emil)" not in running, running
    assert takeover["removed"] == [RETRACTED] and takeover["added"] == [], takeover
    served = _events(read_trace(emil_trace), "call", after=t)
    assert any(all(r.get(k) == v for k, v in SERVED.items()) for r in served)
    _served_to_the_end(tmp_path, again_trace, takeover)
