"""A helper whose stop hook blocks, across processes over Zenoh (5.5).

Emil coordinates cross-door step 2 (6.2.2); his compass fails and the
society switches 44 -> 47, which stops two of Pippi's functionalities. Pippi's
stop hooks block for good. Before, Pippi froze in the first hook
(the switch never completed there, her trace called it nothing) and SIGTERM
did not end her. Now each hook is abandoned after the call budget, reported
as a failure of its functionality on Pippi's terminal and in her trace, the
switch completes, the coordinator's console says what her hook did, and
SIGTERM ends both processes. Hermetic: loopback, free
ports, scouting off, bounded waits, every process stopped by its pid.
"""

from __future__ import annotations

import os
import signal
from pathlib import Path

import pytest

from tests.backends.support import DOMAINS, EXAMPLE_IMPL
from tests.runtime.netutil import (
    endpoint,
    first,
    free_port,
    hermetic_config,
    processes,
    read_trace,
    wait_for,
)

STEP2 = [
    str(DOMAINS / "cross-door/domain.lisp"),
    str(DOMAINS / "cross-door/state-6.2.2-step2.lisp"),
]
LIMIT = 90.0  # seconds: two interpreters, a Zenoh handshake and a switch, on a loaded machine

BLOCKING_STOP = """
import dataclasses as _dataclasses
import time as _time

from cfgplan.runtime import Implementation as _Implementation

for _name, _value in list(globals().items()):  # every stop hook blocks
    if isinstance(_value, _Implementation):
        globals()[_name] = _dataclasses.replace(_value, stop=lambda *objects: _time.sleep(3600))
"""


@pytest.mark.slow
def test_a_helpers_blocking_stop_hook_is_a_failure_and_sigterm_ends_it(tmp_path: Path) -> None:
    blocking = tmp_path / "blocking.py"
    blocking.write_text(EXAMPLE_IMPL.read_text(encoding="utf-8") + BLOCKING_STOP, "utf-8")
    config = str(hermetic_config(tmp_path))
    port = free_port()
    common = ["--zenoh-config", config, "--society", "stop-hook-test", "--lease", "1"]
    common += ["--rate", "20", "--budget", "0.3"]
    emil_trace, pippi_trace = tmp_path / "emil.jsonl", tmp_path / "pippi.jsonl"
    run = ["-m", "cfgplan", "run", *STEP2]
    with processes() as running:
        emil_args = ["--robot", "Emil", "--impl", str(EXAMPLE_IMPL), "--trace", str(emil_trace)]
        emil_args += ["--listen", endpoint(port), "--inject", "fail compass(Emil) at cycle 40"]
        emil = running.start([*run, *emil_args, *common], tmp_path / "emil.log")
        pippi_args = ["--robot", "Pippi", "--impl", str(blocking), "--trace", str(pippi_trace)]
        pippi_args += ["--listen", endpoint(free_port()), "--connect", endpoint(port)]
        pippi = running.start([*run, *pippi_args, *common], tmp_path / "pippi.log")
        wait_for("Emil sees Pippi", first(emil_trace, lambda r: r["event"] == "robot-seen"), LIMIT)
        installed = wait_for(
            "Pippi installs configuration 1",
            first(pippi_trace, lambda r: r["event"] == "install" and r["id"] == 1),
            30,
        )
        wait_for("the switch", first(emil_trace, lambda r: r["event"] == "switch"), 20)
        told = wait_for(  # the coordinator's console says what Pippi's hook did
            "Emil told of Pippi's hook",
            first(emil_trace, lambda r: r["event"] == "error" and "stop hook" in str(r)),
            20,
        )
        for process in (pippi, emil):
            os.kill(process.pid, signal.SIGTERM)
        assert pippi.wait(20) == 1  # a functionality failed
        assert emil.wait(20) == 0
    assert str(told["message"]).startswith("Pippi F")
    assert "its stop hook took longer than its time budget of 0.3 s" in str(told["message"])
    problems = installed["problems"]
    assert isinstance(problems, list) and len(problems) == 2
    assert all("its stop hook took longer than its time budget of 0.3 s" in p for p in problems)
    timeouts = [r for r in read_trace(pippi_trace) if r.get("status") == "timeout"]
    assert sorted(str(r["functionality"]) for r in timeouts) == [
        "compass",
        "measure-robot-orient-compass",
    ]
    log = (tmp_path / "pippi.log").read_text(encoding="utf-8")
    assert "compass(Pippi) failed: its stop hook took longer than its time budget" in log
    assert "Traceback" not in log
