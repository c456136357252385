"""A robot run from emitted code is passed over in the order, and follows the successor (5.5).

The watch domain (tests/reconfigure/data/watch): Pippi keeps the log of what
Emil's camera sees of Door1, or Rasmus does; the goal names all three, so the
order of succession is Pippi, Emil, Rasmus. Each robot is its own process,
all clients of a router. Pippi owns the goal and coordinates; Rasmus runs
the problem too (``cfgplan run --robot``), empty; Emil runs the program
``cfgplan emit`` wrote for him, which announces the same problem but has no
planner: he never takes over. Pippi is killed: Rasmus takes over — Emil,
next in the order, says he does not plan and is passed over — and switches
the society to Rasmus keeping the log; Emil's program installs Rasmus's
switch, and the log has data again. Pippi started again steps down for
Rasmus, and the society goes on under his run.

Before, every robot that ran the problem took Emil for the successor: nobody
took over, and the goal went unserved for good. Hermetic: loopback, free
ports, scouting off, bounded waits, every process stopped by its pid
(:mod:`tests.runtime.netutil`).
"""

from __future__ import annotations

import os
import signal
import time
from pathlib import Path
from subprocess import Popen

import pytest
from typer.testing import CliRunner

from tests.reconfigure.test_network_restart import _after
from tests.reconfigure.test_network_takeover import LEASE, LIMIT, _events
from tests.runtime.netutil import (
    Processes,
    endpoint,
    first,
    free_port,
    processes,
    read_trace,
    wait_for,
)

WATCH = Path(__file__).resolve().parent / "data" / "watch"
DOMAIN, STATE, IMPL = WATCH / "domain.lisp", WATCH / "state.lisp", WATCH / "impl.py"
TAKEOVER_LIMIT = 20.0  # seconds: far beyond the lease and 1 s the takeover takes
LOGGED = {"functionality": "keep-log", "status": "ran"}


def _planner(
    running: Processes, folder: Path, name: str, net: list[str]
) -> tuple[Popen[str], Path]:
    """``cfgplan run --robot NAME`` of the watch; its process and trace."""
    trace = folder / f"{name.lower()}.jsonl"
    args = ["-m", "cfgplan", "run", str(DOMAIN), str(STATE), "--robot", name]
    args += ["--impl", str(IMPL), "--rate", "20", "--duration", "120", "--trace", str(trace)]
    return running.start([*args, *net], folder / f"{name.lower()}.log"), trace


@pytest.mark.slow
def test_the_successor_passes_over_an_emitted_robot_which_follows_it(tmp_path: Path) -> None:
    import cfgplan.cli.emit  # noqa: F401  (loads the command module)
    from cfgplan.cli.app import app

    out = tmp_path / "emitted"
    emitted = CliRunner().invoke(app, ["emit", str(DOMAIN), str(STATE), "-o", str(out)])
    assert emitted.exit_code == 0, emitted.output
    router = endpoint(free_port())
    net = ["--society", "takeover-emitted", "--router", router, "--lease", f"{LEASE:g}"]
    with processes() as running:
        log = tmp_path / "router.log"
        running.start(["-m", "cfgplan", "router", "--listen", router, "--lease", "1"], log)
        wait_for("the router", lambda: {} if "listening" in log.read_text("utf-8") else None, 60)
        _, rasmus_trace = _planner(running, tmp_path, "Rasmus", net)
        emil_trace = tmp_path / "emil.jsonl"
        emil = [str(out / "emil.py"), "--impl", str(IMPL), "--rate", "20", "--duration", "120"]
        running.start([*emil, "--trace", str(emil_trace), *net], tmp_path / "emil.log")
        pippi, pippi_trace = _planner(running, tmp_path, "Pippi", net)
        wait_for("Pippi's log served", _after(pippi_trace, 0.0, "call", **LOGGED), LIMIT)
        # a second of hers: her token has reached everyone (Rasmus cannot lose what he never saw)
        wait_for("Pippi for a second", first(pippi_trace, lambda r: r["cycle"] >= 20), LIMIT)
        os.kill(pippi.pid, signal.SIGKILL)
        killed = time.time()
        takeover = wait_for(
            "Rasmus takes over", _after(rasmus_trace, killed, "takeover"), TAKEOVER_LIMIT
        )
        t = float(takeover["t"])  # type: ignore[arg-type]
        switch = wait_for("Rasmus's switch", _after(rasmus_trace, t - 1e-6, "switch"), 10.0)
        logged = wait_for(
            "the log served again", _after(rasmus_trace, float(switch["t"]), "call", **LOGGED), 10.0
        )  # type: ignore[arg-type]
        # Emil's program, still running: his trace is read once what it must hold is in it
        epoch = str(takeover["epoch"])
        obeyed = _after(emil_trace, killed, "install", epoch=epoch, leader="Rasmus")
        wait_for("Emil installs Rasmus's switch", obeyed, 10.0)
        detects = _after(emil_trace, t, "call", functionality="detect", status="ran")
        wait_for("Emil's detection runs under Rasmus", detects, 10.0)
        again = tmp_path / "again"
        again.mkdir()
        _, back_trace = _planner(running, again, "Pippi", net)
        down = wait_for("Pippi steps down", _after(back_trace, 0.0, "step-down"), LIMIT)
        stepped = float(down["t"])  # type: ignore[arg-type]
        wait_for("the log after", _after(rasmus_trace, stepped + 1.0, "call", **LOGGED), 10.0)
    assert (takeover["robot"], takeover["after"], takeover["step"]) == ("Rasmus", "Pippi", 0)
    assert epoch.startswith("2.") and t - killed < LEASE + 1.0, (epoch, t - killed)
    # After the fault: Rasmus keeps the log, Emil's program obeys his run alone.
    assert switch["to_cost"] == 27 and switch["cause"] == "takeover from Pippi", switch
    started = switch["started"]["functionalities"]  # type: ignore[index]
    assert any(f.endswith(": keep-log(Rasmus, Door1)") for f in started), started
    assert float(logged["t"]) - killed < LEASE + 3.0  # type: ignore[arg-type]
    his = read_trace(emil_trace)
    installs = _events(his, "install", after=killed)
    assert installs and {(r["epoch"], r["leader"]) for r in installs} == {(epoch, "Rasmus")}
    ran = [r for r in _events(his, "call", after=t) if r["functionality"] == "detect"]
    assert any(r["status"] == "ran" for r in ran)
    # Pippi back follows Rasmus: nothing of hers is obeyed, nothing switches back.
    assert (down["leader"], down["epoch"]) == ("Rasmus", epoch)
    assert _events(read_trace(back_trace), "switch", after=stepped) == []
    assert _events(read_trace(rasmus_trace), "switch", after=float(switch["t"])) == []  # type: ignore[arg-type]
