"""A sequence of configurations run across processes over Zenoh ends well for every robot.

In the 6.2.2 sequence run with each robot its own process, Pippi
(who owns the first goal) coordinates; when Emil's crossing, the last step,
is accomplished she told Emil to finish and left at once, so Emil's terminal
never said the task was accomplished and its last line was ``robot Pippi
lost``. Now the coordinator waits (bounded) for every robot to answer the
finish: each says the task is accomplished, exits 0, and nobody reports a
robot that left after finishing as lost. Hermetic: loopback, free ports,
scouting off, bounded waits, every process stopped by its pid
(:mod:`tests.runtime.netutil`).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from cfgplan.runtime.schema import TRACE_EVENT
from tests.backends.support import DOMAINS, ROOT
from tests.runtime.netutil import endpoint, free_port, hermetic_config, processes, read_trace

SEQUENCE = [
    str(DOMAINS / "cross-door/domain-steps.lisp"),
    str(DOMAINS / "cross-door/state-6.2.2-sequence.lisp"),
]
STEPS = ROOT / "examples" / "cross-door" / "steps.py"
LIMIT = 120.0  # seconds: two interpreters, a Zenoh handshake and two crossings of 100 calls


@pytest.mark.slow
def test_every_robot_of_a_sequence_over_zenoh_ends_saying_the_task_is_accomplished(
    tmp_path: Path,
) -> None:
    config = str(hermetic_config(tmp_path))
    port = free_port()
    common = ["--zenoh-config", config, "--society", "sequence-test", "--lease", "1"]
    networks = {
        "Emil": ["--listen", endpoint(port), *common],
        "Pippi": ["--listen", endpoint(free_port()), "--connect", endpoint(port), *common],
    }
    with processes() as running:
        started = {}
        for name in ("Emil", "Pippi"):  # the helper first; Pippi owns the goal, coordinates
            args = ["-m", "cfgplan", "run", *SEQUENCE, "--robot", name, "--impl", str(STEPS)]
            args += ["--rate", "50", "--trace", str(tmp_path / f"{name}.jsonl"), *networks[name]]
            started[name] = running.start(args, tmp_path / f"{name}.log")
        assert started["Pippi"].wait(LIMIT) == 0
        assert started["Emil"].wait(LIMIT) == 0
    logs = {name: (tmp_path / f"{name}.log").read_text() for name in started}
    traces = {name: read_trace(tmp_path / f"{name}.jsonl") for name in started}
    pippi = [r for r in traces["Pippi"] if r["event"] in ("achieved", "switch", "finish")]
    assert [r["event"] for r in pippi] == ["achieved", "switch", "achieved", "finish"]
    assert pippi[-1]["silent"] == []  # Emil answered before Pippi left
    (finish,) = [r for r in traces["Emil"] if r["event"] == "finish"]
    assert (finish["from"], finish["goal"]) == ("Pippi", "do-cross-door(Emil, Door1)")
    assert [r["reason"] for r in traces["Emil"] if r["event"] == "stop"] == ["achieved"]
    assert not [r for name in started for r in traces[name] if r["event"] == "robot-lost"]
    emil = [line for line in logs["Emil"].splitlines() if line.startswith("cycle ")]
    assert emil[-1].endswith(
        "Emil: the task is accomplished (do-cross-door(Emil, Door1), says Pippi): the run ends"
    )
    pippi_lines = [line for line in logs["Pippi"].splitlines() if line.startswith("cycle ")]
    assert pippi_lines[-1].endswith(
        "Pippi: every robot knows the task is accomplished: the run ends"
    )
    for log in logs.values():
        assert " lost" not in log and "Traceback" not in log
    for name in started:  # both kinds of finish follow the documented schema
        for line in (tmp_path / f"{name}.jsonl").read_text(encoding="utf-8").splitlines():
            TRACE_EVENT.validate_json(line)
