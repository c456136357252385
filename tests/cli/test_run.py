"""``cfgplan run``: the configuration executed in process, or one robot's part (chapter 5)."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest
from typer.testing import CliRunner

import cfgplan.cli.run  # noqa: F401  (loads the command module)
from cfgplan.cli.app import app
from cfgplan.diagnostics import CfgplanError
from tests.backends.support import CROSS, DOMAINS, EXAMPLE_IMPL, ROOT, cross_door_44
from tests.runtime.netutil import first, processes, wait_for

ARGS = [str(DOMAINS / CROSS[0]), str(DOMAINS / CROSS[1])]
FAST = ["--impl", str(EXAMPLE_IMPL), "--rate", "0"]


def test_run_prints_what_cross_door_received() -> None:
    _, config = cross_door_44()
    (label,) = [f.label for f in config.functionalities if f.name == "cross-door"]
    result = CliRunner().invoke(app, ["run", *ARGS, *FAST, "--cycles", "3"])
    assert result.exit_code == 0, result.output
    lines = result.output.splitlines()
    assert (
        lines[0]
        == "Configuration rank 1, cost 44, for do-cross-door(Pippi, Door1): Pippi, Emil; 3 cycle(s)"
    )
    received = [line for line in lines if " received " in line]
    assert [line.split(":")[0] for line in received] == ["cycle 2"]  # when it starts to
    assert received[0].startswith(
        f"cycle 2: Pippi {label} cross-door(Pippi, Door1) received pos(Pippi, Door1) = ["
    )
    assert f"Pippi {label} cross-door(Pippi, Door1): ran in 2 of 3 cycles" in lines


def test_run_verbose_shows_every_call_and_rank_2_runs_too() -> None:
    """Rank 2 (cost 47, cameras only, Fig. 6.4) runs on the same implementations."""
    result = CliRunner().invoke(
        app, ["run", *ARGS, *FAST, "--rank", "2", "--cycles", "2", "--verbose"]
    )
    assert result.exit_code == 0, result.output
    assert "cost 47" in result.output.splitlines()[0]
    assert "measure-robot-orient-camera(Emil, Pippi) read angle(Emil, Pippi) = " in result.output
    assert (
        "cross-door(Pippi, Door1) waits for pos(Pippi, Door1), orient(Pippi, Door1)"
        in result.output
    )


def test_run_writes_the_trace_and_refuses_to_overwrite_it(tmp_path: Path) -> None:
    trace = tmp_path / "run.jsonl"
    args = ["run", *ARGS, *FAST, "--cycles", "2", "--trace", str(trace)]
    assert CliRunner().invoke(app, args).exit_code == 0
    lines = [json.loads(x) for x in trace.read_text().splitlines()]
    assert [e["event"] for e in lines[:2]] == ["start", "start"]
    assert lines[-1] == {**lines[-1], "event": "stop", "robot": "Emil", "reason": "cycles"}
    assert all({"event", "robot", "t"} <= set(e) for e in lines)
    calls = [e for e in lines if e["event"] == "call"]
    assert len(calls) == 2 * 8
    before = trace.read_bytes()
    again = CliRunner().invoke(app, args)
    assert again.exit_code == 1
    assert isinstance(again.exception, CfgplanError)
    assert "exists; pass --force to overwrite it" in str(again.exception)
    assert trace.read_bytes() == before
    assert CliRunner().invoke(app, [*args, "--force"]).exit_code == 0


def test_run_one_robot_and_what_is_refused() -> None:
    alone = CliRunner().invoke(
        app, ["run", *ARGS, *FAST, "--robot", "Emil", "--transport", "inprocess", "--cycles", "2"]
    )
    assert alone.exit_code == 0, alone.output
    assert ": Emil; 2 cycle(s)" in alone.output.splitlines()[0]
    assert "waits for global-orient(Pippi)" in alone.output
    unknown = CliRunner().invoke(app, ["run", *ARGS, *FAST, "--robot", "Ada"])
    assert unknown.exit_code == 1
    assert str(unknown.exception) == (
        "no robot Ada in this configuration (its robots: Pippi, Emil)"
    )
    usage = CliRunner().invoke(app, ["run", *ARGS, *FAST, "--transport", "zenoh"])
    assert usage.exit_code == 2 and "--robot NAME" in usage.output
    bad = CliRunner().invoke(app, ["run", *ARGS, *FAST, "--robot", "Emil", "--listen", "7447"])
    assert bad.exit_code == 2 and "an endpoint is PROTOCOL/ADDRESS" in bad.output


def test_run_without_an_implementation_fails_clearly() -> None:
    carry = [str(DOMAINS / "carry-bar/domain.lisp"), str(DOMAINS / "carry-bar/state-6.3.2.lisp")]
    result = CliRunner().invoke(app, ["run", *carry, "--impl", str(EXAMPLE_IMPL)])
    assert result.exit_code == 1
    message = str(result.exception)
    # every missing one at once, before anything runs
    assert (
        "no implementation of functionalities calc-robot-speed-diff, laser, lead-robot, " in message
    )
    assert "meas-robot-angle-dist-laser, stalk-robot in " in message


def test_run_a_rank_that_does_not_exist_exits_3() -> None:
    result = CliRunner().invoke(app, ["run", *ARGS, "--impl", str(EXAMPLE_IMPL), "--rank", "9"])
    assert result.exit_code == 3


@pytest.mark.slow
def test_a_broken_implementation_file_is_shown_with_a_caret(tmp_path: Path) -> None:
    """The implementation's fault, file:line:col, no traceback."""
    impl = tmp_path / "impl.py"
    impl.write_text("import math\nPOSE = (1.0, 2.0\n")
    out = subprocess.run(
        [sys.executable, "-m", "cfgplan", "run", *ARGS, "--impl", str(impl)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert out.returncode == 1
    assert "Traceback" not in out.stderr
    lines = out.stderr.splitlines()
    assert lines[0].startswith(f"{impl}:2:8: error: the implementations in {impl} do not compile")
    assert lines[1:3] == ["    2 | POSE = (1.0, 2.0", "      |        ^"]


def test_an_implementation_of_the_wrong_arity_is_refused_before_the_run(tmp_path: Path) -> None:
    """Refused at start, naming the functionality and the function
    with its file and line, not on the first call; the emitted run_all.py too."""
    impl = tmp_path / "impl.py"
    text = EXAMPLE_IMPL.read_text(encoding="utf-8")
    wrong = "def measure_door(door: str) -> tuple[Pos, float] | None:"
    text = text.replace(
        "def measure_door(door: str, image: Image) -> tuple[Pos, float] | None:", wrong
    )
    assert wrong in text
    impl.write_text(text, encoding="utf-8")
    line = text[: text.index(wrong)].count("\n")  # the decorator's line, as Python reports it
    emitted = tmp_path / "out"
    done = CliRunner().invoke(app, ["emit", *ARGS, "--lang", "python", "-o", str(emitted)])
    assert done.exit_code == 0, done.output
    commands = (
        [sys.executable, "-m", "cfgplan", "run", *ARGS, "--impl", str(impl), "--cycles", "3"],
        [sys.executable, str(emitted / "run_all.py"), "--impl", str(impl), "--cycles", "3"],
    )
    for command in commands:
        out = subprocess.run(command, cwd=ROOT, capture_output=True, text=True, timeout=60)
        assert out.returncode == 1, out.stderr
        assert "Traceback" not in out.stderr
        first = out.stderr.splitlines()[0]
        assert first.startswith(f"{impl}:{line}:1: error: the function measure_door declared for ")
        assert "measure-door cannot be called as F9: measure-door(Emil, Door1) calls it, " in first
        assert "with 1 object argument then 1 input (in :in order): too many" in first
        assert "received" not in out.stdout  # nothing ran


THREE = """(state robot(Pippi), robot(Emil), robot(Rasmus), door(Door1),
       camera(Pippi), camera(Emil), camera(Rasmus), compass(Pippi), compass(Emil),
       compass(Rasmus), in(Pippi, Room1), in(Emil, Room1), in(Rasmus, Room1),
       in(Door1, Room1), open(Door1), connects(Door1, Room1, Room2))
(goal (do-cross-door Pippi Door1))
"""
"""Cross-door with a third robot: Emil helps (44); lost, Rasmus takes over (44)."""


def test_cycles_count_the_goal_robot_after_a_robot_joins(tmp_path: Path) -> None:
    """With a rate, ``--cycles 40`` stopped after 40 passes of the loop,
    and a robot that joins on a switch (Rasmus, on a beat of his own) made
    passes outnumber Pippi's cycles (25 of 40). Now Pippi runs 40 cycles."""
    state = tmp_path / "three.lisp"
    state.write_text(THREE, encoding="utf-8")
    impl = tmp_path / "impl.py"
    extra = '\nWORLD["Rasmus"] = (0.5, -2.2, 0.3)\n'
    impl.write_text(EXAMPLE_IMPL.read_text(encoding="utf-8") + extra, encoding="utf-8")
    trace = tmp_path / "run.jsonl"
    args = [str(DOMAINS / CROSS[0]), str(state), "--impl", str(impl), "--rate", "50"]
    args += ["--cycles", "40", "--inject", "kill Emil at cycle 10", "--trace", str(trace)]
    result = CliRunner().invoke(app, ["run", *args])
    assert result.exit_code == 0, result.output
    events = [json.loads(x) for x in trace.read_text().splitlines()]
    started = [e["started"] for e in events if e["event"] == "switch"]
    assert len(started) == 1 and "F15: transform-info(Rasmus, Pippi, Door1)" in str(started)
    rasmus = {e["cycle"] for e in events if e["event"] == "call" and e["robot"] == "Rasmus"}
    assert rasmus, "Rasmus joined and ran"
    pippi = [e for e in events if e["event"] == "call" and e["functionality"] == "compass"]
    assert [e["cycle"] for e in pippi if e["robot"] == "Pippi"] == list(range(1, 41))
    assert "Pippi F10 compass(Pippi): ran in 40 of 40 cycles" in result.output


BLOCKING_STOP = """
import dataclasses as _dataclasses
import time as _time

from cfgplan.runtime import Implementation as _Implementation

for _name, _value in list(globals().items()):  # every stop hook blocks
    if isinstance(_value, _Implementation):
        globals()[_name] = _dataclasses.replace(_value, stop=lambda *objects: _time.sleep(3600))
"""


@pytest.mark.slow
def test_a_stop_hook_that_blocks_neither_freezes_the_switch_nor_outlives_sigterm(
    tmp_path: Path,
) -> None:
    """A switch whose stop hook blocks froze the run for good, and
    SIGTERM did not end it. Now the hook is abandoned after the call budget,
    its functionality is reported failed, the switch goes on, and SIGTERM ends
    the process."""
    impl = tmp_path / "impl.py"
    impl.write_text(EXAMPLE_IMPL.read_text(encoding="utf-8") + BLOCKING_STOP, encoding="utf-8")
    trace = tmp_path / "run.jsonl"
    step2 = str(DOMAINS / "cross-door/state-6.2.2-step2.lisp")
    args = ["-m", "cfgplan", "run", ARGS[0], step2, "--impl", str(impl), "--rate", "50"]
    args += ["--budget", "0.3", "--inject", "fail compass(Emil) at cycle 5"]
    args += ["--trace", str(trace)]
    with processes() as running:
        run = running.start(args, tmp_path / "run.log")
        wait_for("the switch", first(trace, lambda e: e["event"] == "switch"), 30)
        hook = first(trace, lambda e: e.get("status") == "timeout")
        failed = wait_for("the hook reported", hook, 10)
        assert "its stop hook took longer than its time budget of 0.3 s" in str(failed["error"])
        os.kill(run.pid, signal.SIGTERM)
        assert run.wait(timeout=10) == 1  # a functionality failed
    log = (tmp_path / "run.log").read_text(encoding="utf-8")
    assert "its stop hook took longer than its time budget of 0.3 s; abandoned" in log


def test_the_trace_is_capped_and_rotates_once(tmp_path: Path) -> None:
    """Traces grew without a cap. ``--trace-max-bytes`` caps FILE;
    past it FILE becomes FILE.1 and a new FILE begins."""
    trace = tmp_path / "run.jsonl"
    args = ["run", *ARGS, *FAST, "--cycles", "60", "--trace", str(trace)]
    result = CliRunner().invoke(app, [*args, "--trace-max-bytes", "20000"])
    assert result.exit_code == 0, result.output
    older = tmp_path / "run.jsonl.1"
    assert trace.stat().st_size <= 20_000 and 10_000 < older.stat().st_size <= 20_000
    last = json.loads(trace.read_text().splitlines()[-1])
    assert last["event"] == "stop" and last["reason"] == "cycles"


def test_max_value_bytes_is_a_run_option() -> None:
    """Cross-door's values are small: a limit of 10 bytes refuses its global outputs."""
    args = ["run", *ARGS, *FAST, "--cycles", "3", "--max-value-bytes", "10"]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 1
    assert "over the limit of 10 bytes (--max-value-bytes); not sent" in result.output
    bad = CliRunner().invoke(app, ["run", *ARGS, *FAST, "--max-value-bytes", "-1"])
    assert bad.exit_code == 2 and "Traceback" not in bad.output


@pytest.mark.parametrize(
    ("fault", "says"),
    [
        ("kill Emli at cycle 3", "no robot Emli in this society (did you mean Emil?)"),
        ("fail compass(Nobody) at cycle 3", "no robot Nobody in this society"),
        ("fail gizmo(Emil) at cycle 3", "no functionality gizmo in the domain"),
    ],
)
def test_a_fault_aimed_at_nothing_is_a_usage_error(fault: str, says: str) -> None:
    """A newcomer's ``--inject 'kill Emli at cycle 3'`` ran 30 cycles, exit 0,
    with no console line and no ``inject`` event: the fault test tested nothing."""
    args = [str(DOMAINS / CROSS[0]), str(DOMAINS / "cross-door/state-6.2.2-step2.lisp")]
    args += ["--impl", str(EXAMPLE_IMPL), "--cycles", "3", "--inject", fault]
    result = CliRunner().invoke(app, ["run", *args])
    assert result.exit_code == 2, result.output
    assert says in " ".join(result.output.split())
