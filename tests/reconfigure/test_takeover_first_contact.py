"""A coordinator lost before anyone heard from it is taken over too (5.5).

The 6.2.2 sequence, each robot its own process, both clients of a router
(:mod:`cfgplan.runtime.router`). Pippi, who owns the first goal, starts and
coordinates; she is frozen (SIGSTOP) before Emil starts, so that Emil sees
her token — the router keeps it while her lease runs — but never a message
of hers. She is then killed: the router drops her at once, and Emil, who
expected her to coordinate, takes over within the lease and 1 s, though her
run never reached him. Pippi started again steps down for him, and the
sequence is served to its end under his run (every switch Emil obeys is
his own run's: he never heard Pippi's first one).

Before, a robot knew its coordinator only from the first message of its run:
Emil never took over, and waited for good. Hermetic: loopback, free ports,
scouting off, bounded waits, every process stopped by its pid
(:mod:`tests.runtime.netutil`).
"""

from __future__ import annotations

import os
import signal
import time
from pathlib import Path

import pytest

from tests.reconfigure.test_network_restart import _after
from tests.reconfigure.test_network_takeover import (
    LEASE,
    LIMIT,
    _events,
    _served_to_the_end,
    _start,
    _taken_over_then_back,
)
from tests.runtime.netutil import endpoint, free_port, processes, read_trace, wait_for

HELD = 30  # seconds the router keeps a frozen Pippi (her lease): Emil starts meanwhile
TAKEOVER_LIMIT = 20.0  # seconds: far beyond the lease and 1 s the takeover takes


@pytest.mark.slow
def test_a_coordinator_killed_before_first_contact_is_taken_over(tmp_path: Path) -> None:
    router = endpoint(free_port())
    society = ["--society", "takeover-first", "--router", router]
    with processes() as running:
        log = tmp_path / "router.log"
        running.start(["-m", "cfgplan", "router", "--listen", router, "--lease", "1"], log)
        wait_for("the router", lambda: {} if "listening" in log.read_text("utf-8") else None, 60)
        pippi, pippi_trace, _ = _start(running, tmp_path, "Pippi", [*society, "--lease", str(HELD)])
        wait_for("Pippi runs", _after(pippi_trace, 0.0, "start"), LIMIT)
        os.kill(pippi.pid, signal.SIGSTOP)  # type: ignore[attr-defined]
        frozen = time.time()
        emil, emil_trace, _ = _start(running, tmp_path, "Emil", [*society, "--lease", f"{LEASE:g}"])
        seen = wait_for("Emil sees Pippi", _after(emil_trace, 0.0, "robot-seen", other="Pippi"), 20)
        assert time.time() - frozen < HELD - 5, "Emil saw Pippi too late to trust the test"
        os.kill(pippi.pid, signal.SIGKILL)  # type: ignore[attr-defined]
        killed = time.time()
        back = [*society, "--lease", f"{LEASE:g}"]
        takeover, again_trace = _taken_over_then_back(
            running, tmp_path, emil, back, killed, TAKEOVER_LIMIT
        )
    t = float(takeover["t"])  # type: ignore[arg-type]
    assert float(seen["t"]) > frozen  # type: ignore[arg-type]
    assert (takeover["after"], takeover["step"]) == ("Pippi", 0)
    assert str(takeover["epoch"]).startswith("2.")  # past the run he never heard: the first
    assert t - killed < LEASE + 1.0, t - killed
    emil = read_trace(emil_trace)
    assert _events(emil, "install", after=0.0) == _events(emil, "install", after=t)
    _served_to_the_end(tmp_path, again_trace, takeover)
