"""The emitted programs' command line: options, faults of implementations, clean
stops (Ctrl-C, SIGTERM) with the summary, and where --trace may write."""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
from pathlib import Path

import pytest
from typer.testing import CliRunner

import cfgplan.cli.emit  # noqa: F401  (loads the command module)
from cfgplan.cli.app import app
from cfgplan.runtime.console import WAIT_NOTICE
from tests.backends.support import CROSS, DOMAINS, EXAMPLE_IMPL, ROOT
from tests.runtime.netutil import first, processes, read_trace, wait_for

FAULTY = f"""
import sys, threading
from cfgplan.runtime import Implementation, functionality, load_module

example = load_module(__import__("pathlib").Path({str(EXAMPLE_IMPL)!r}))
globals().update(
    {{k: v for k, v in vars(example).items()
      if isinstance(v, Implementation) and v.name not in ("camera", "compass")}}
)
calls = []

@functionality("camera")
def camera():
    calls.append(1)
    if len(calls) == 2:
        sys.exit(4)
    if len(calls) == 3:
        threading.Event().wait(60)  # blocks: over the time budget
    return example.camera.function()

@functionality("compass")
def compass():
    return example.compass.function()
"""


@pytest.fixture(scope="module")
def emitted(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("emitted")
    args = ["emit", *(str(DOMAINS / f) for f in CROSS), "--lang", "python", "-o", str(out)]
    assert CliRunner().invoke(app, args).exit_code == 0
    return out


def _run(script: Path, *args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, str(script), *args],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=60,
    )


@pytest.mark.parametrize(
    "args",
    [
        ["--rate", "-1"],
        ["--cycles", "two"],
        ["--duration", "0"],
        ["--budget", "nan"],
        ["--transport", "carrier-pigeon"],
        ["--listen", "7447"],
        ["--lease", "0"],
    ],
)
def test_bad_options_are_usage_errors(emitted: Path, args: list[str]) -> None:
    out = _run(emitted / "emil.py", "--impl", str(EXAMPLE_IMPL), *args)
    assert out.returncode == 2
    assert "Traceback" not in out.stderr and "error: argument" in out.stderr


def test_faulty_implementations_are_reported_and_the_society_goes_on(
    emitted: Path, tmp_path: Path
) -> None:
    """Emil's camera calls sys.exit on its second call and blocks on its third:
    both reported, naming the functionality; the compasses and the other
    functionalities keep running; exit status 1; no traceback."""
    impl = tmp_path / "faulty.py"
    impl.write_text(FAULTY)
    trace = tmp_path / "trace.jsonl"
    out = _run(
        emitted / "run_all.py",
        "--impl",
        str(impl),
        "--rate",
        "0",
        "--cycles",
        "6",
        "--budget",
        "0.3",
        "--trace",
        str(trace),
    )
    assert out.returncode == 1, out.stderr
    assert "Traceback" not in out.stderr + out.stdout
    err = out.stderr.splitlines()
    exited = "failed: the implementation called sys.exit(4)"
    assert f"cfgplan: cycle 2: Emil F8 camera(Emil) {exited} [{impl}]" in err
    assert any(
        line.startswith(
            "cfgplan: cycle 3: Emil F8 camera(Emil) failed: the call took longer "
            "than its time budget of 0.3 s"
        )
        for line in err
    )
    lines = out.stdout.splitlines()
    assert "Pippi F10 compass(Pippi): ran in 6 of 6 cycles" in lines
    assert (
        "Emil F8 camera(Emil): ran in 1 of 6 cycles; timed out 1 time; failed 1 time, last: "
        "the implementation called sys.exit(4)"
    ) in lines
    statuses = [r["status"] for r in read_trace(trace) if r.get("functionality") == "camera"]
    assert statuses == ["ran", "error", "timeout", "busy", "busy", "busy"]


def test_sigterm_and_ctrl_c_stop_cleanly_with_the_summary(emitted: Path, tmp_path: Path) -> None:
    for sig, reason in ((signal.SIGTERM, "terminated"), (signal.SIGINT, "interrupted")):
        trace = tmp_path / f"{reason}.jsonl"
        log = tmp_path / f"{reason}.log"
        with processes() as running:
            society = running.start(
                [
                    str(emitted / "run_all.py"),
                    "--impl",
                    str(EXAMPLE_IMPL),
                    "--rate",
                    "50",
                    "--trace",
                    str(trace),
                ],
                log,
            )
            wait_for("a few cycles", first(trace, lambda r: int(r["cycle"]) >= 5), 60.0)
            os.kill(society.pid, sig)
            assert society.wait(timeout=30) == 0
        text = log.read_text()
        assert "Traceback" not in text
        assert "Pippi F3 cross-door(Pippi, Door1): ran in " in text
        stops = [r for r in read_trace(trace) if r["event"] == "stop"]
        assert [(r["robot"], r["reason"]) for r in stops] == [
            ("Pippi", reason),
            ("Emil", reason),
        ]


def test_run_all_refuses_a_fault_aimed_at_no_robot_of_it(emitted: Path) -> None:
    """Every robot runs in run_all.py: a fault aimed at another name is a typo,
    refused as usage (exit 2) before anything runs, not silently dropped."""
    args = ["--impl", str(EXAMPLE_IMPL), "--rate", "0", "--cycles", "3"]
    out = _run(emitted / "run_all.py", *args, "--inject", "kill Emli at cycle 2")
    assert out.returncode == 2, out.stderr
    assert "no robot Emli in this society (did you mean Emil?)" in out.stderr
    assert out.stdout == ""
    ok = _run(emitted / "run_all.py", *args, "--inject", "kill Emil at cycle 2")
    assert ok.returncode == 0, ok.stderr
    assert "inject" in ok.stdout and "kill Emil" in ok.stdout


def test_the_trace_is_not_overwritten_without_force(emitted: Path, tmp_path: Path) -> None:
    trace = tmp_path / "trace.jsonl"
    trace.write_text("kept\n")
    args = ["--impl", str(EXAMPLE_IMPL), "--rate", "0", "--cycles", "1", "--trace", str(trace)]
    out = _run(emitted / "run_all.py", *args)
    assert out.returncode == 1
    assert out.stderr == f"error: trace file {trace} exists; pass --force to overwrite it\n"
    assert trace.read_text() == "kept\n"
    forced = _run(emitted / "run_all.py", *args, "--force")
    assert forced.returncode == 0
    assert json.loads(trace.read_text().splitlines()[0])["event"] == "start"


def test_a_robot_alone_over_zenoh_waits_and_stops_after_its_duration(
    emitted: Path, tmp_path: Path
) -> None:
    """python emil.py with nobody to talk to: it runs, waits for Pippi's
    compass, and stops after --duration with its summary."""
    from tests.runtime.netutil import endpoint, free_port, hermetic_config

    out = _run(
        emitted / "emil.py",
        "--impl",
        str(EXAMPLE_IMPL),
        "--duration",
        "0.5",
        "--listen",
        endpoint(free_port()),
        "--zenoh-config",
        str(hermetic_config(tmp_path)),
    )
    assert out.returncode == 0, out.stderr
    assert "Emil F12 measure-robot-orient-compass(Emil, Pippi): ran in 0 of " in out.stdout
    assert "waits for global-orient(Pippi)" in out.stdout


@pytest.mark.slow
def test_a_console_that_cannot_be_written_to_is_said_once(emitted: Path) -> None:
    """stdout to a full disk, or to a pipe closed early: no traceback."""
    args = [str(emitted / "run_all.py"), "--impl", str(EXAMPLE_IMPL), "--rate", "0"]
    if Path("/dev/full").exists():
        with open("/dev/full", "w") as full:
            out = subprocess.run(
                [sys.executable, *args, "--cycles", "5"],
                cwd=ROOT,
                stdout=full,
                stderr=subprocess.PIPE,
                text=True,
                timeout=60,
            )
        assert out.returncode == 1
        assert out.stderr == (
            "cfgplan: error: cannot write to standard output: No space left on device\n"
        )
    piped = subprocess.run(
        f"{sys.executable} {' '.join(args)} --cycles 1000 | head -n 2",
        shell=True,
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=60,
    )
    first, second = piped.stdout.splitlines()
    assert first == "Pippi, Emil: running 1000 cycle(s)"
    assert second.startswith("cycle 2: Pippi F3 cross-door(Pippi, Door1) received ")
    assert "Traceback" not in piped.stderr and "Exception ignored" not in piped.stderr


def test_a_robot_alone_says_what_it_waits_for(emitted: Path) -> None:
    """Run alone, Emil never gets Pippi's compass reading; his program
    says so after WAIT_NOTICE calls instead of looking hung, and says first how
    long it runs, as cfgplan run does."""
    out = _run(
        emitted / "emil.py",
        "--impl",
        str(EXAMPLE_IMPL),
        "--transport",
        "inprocess",
        "--rate",
        "0",
        "--cycles",
        str(WAIT_NOTICE + 5),
    )
    assert out.returncode == 0, out.stderr
    lines = out.stdout.splitlines()
    assert lines[0] == f"Emil: running {WAIT_NOTICE + 5} cycle(s)"
    assert lines[1:3] == [
        f"cycle {WAIT_NOTICE}: Emil F12 measure-robot-orient-compass(Emil, Pippi) waits for "
        f"global-orient(Pippi) ({WAIT_NOTICE} calls in a row so far)",
        f"cycle {WAIT_NOTICE}: Emil F7 transform-info(Emil, Pippi, Door1) waits for "
        f"orient(Emil, Pippi) ({WAIT_NOTICE} calls in a row so far)",
    ]
    assert "waits for" not in "\n".join(lines[3:]).split("ran in")[0]  # said once each


@pytest.mark.slow
def test_run_all_with_respawn_starts_its_society_again_when_its_process_dies(
    emitted: Path, tmp_path: Path
) -> None:
    """``run_all.py --respawn`` runs the society in a process it watches: that
    process killed (SIGKILL) twice, it is started again after 1 s, then 2 s
    (a death in a row doubles the delay), each start tracing to a file of
    its own, and the society runs again (its goal's action ran in the third
    start); SIGTERM then stops it, exit 0. Before, --respawn did not exist
    and a killed run_all.py stayed dead."""
    trace = tmp_path / "run.jsonl"
    log = tmp_path / "run.log"
    with processes() as running:
        supervisor = running.start(
            [str(emitted / "run_all.py"), "--impl", str(EXAMPLE_IMPL), "--rate", "50",
             "--trace", str(trace), "--respawn"],
            log,
        )  # fmt: skip
        for life, file in ((1, trace), (2, tmp_path / "run-2.jsonl")):
            wait_for(f"start {life} runs", first(file, lambda r: int(r["cycle"]) >= 5), 60.0)
            pids = [int(p) for p in re.findall(r"\(started: pid (\d+)", log.read_text())]
            assert len(pids) == life, log.read_text()
            os.kill(pids[-1], signal.SIGKILL)
        third = tmp_path / "run-3.jsonl"
        wait_for(
            "the third start serves the goal",
            first(third, lambda r: r["event"] == "call" and r["functionality"] == "cross-door"),
            60.0,
        )
        os.kill(supervisor.pid, signal.SIGTERM)
        assert supervisor.wait(timeout=30) == 0
        text = log.read_text()
    assert re.findall(r"started again in (\S+) s", text) == ["1", "2"], text
    assert "start 3)" in text and "Traceback" not in text
    stops = [r for r in read_trace(third) if r["event"] == "stop"]
    assert {r["reason"] for r in stops} == {"terminated"}
