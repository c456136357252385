"""Behaviour on big instances: time limits, Ctrl-C and progress (search at scale)."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from benchmarks.families import wall
from cfgplan.configuration.admissible import problems
from cfgplan.planner import plan
from cfgplan.planner.explain import explain, explanation
from cfgplan.planner.options import SearchOptions
from cfgplan.planner.report import Status
from cfgplan.problem import load

ROOT = Path(__file__).resolve().parents[2]


def big(tmp_path: Path) -> tuple[Path, Path]:
    domain, state = wall(8, 50, 20)
    (tmp_path / "d.lisp").write_text(domain)
    (tmp_path / "s.lisp").write_text(state)
    return tmp_path / "d.lisp", tmp_path / "s.lisp"


def test_time_limit_returns_a_configuration_marked_not_proven(tmp_path: Path) -> None:
    """With no time at all the best-first search proves nothing; the dive still
    finds an admissible configuration, marked as not proven optimal."""
    p = load(*big(tmp_path))
    configs, search = plan(p.task, p.goal_call, limit=None, time_limit=0)
    assert search.status is Status.TIME_LIMIT
    assert len(configs) == 1 and not configs[0].proven
    assert problems(configs[0], p.domain, p.state) == []


def test_stopped_with_nothing_found_says_nothing_is_proved(tmp_path: Path) -> None:
    """Stopped before the first expansion ended, and the dive found nothing
    in its grace (a goal with thousands of bindings, 80 robots triangulating
    one): the report said the goal's method had no version, with
    ``complete: true``. Nothing is proved: it says so."""
    p = load(*big(tmp_path))
    configs, search = plan(
        p.task, p.goal_call, limit=1, time_limit=0, options=SearchOptions(dive=False)
    )
    assert configs == [] and search.status is Status.TIME_LIMIT
    lines = explain(search.report, "do-build-wall")
    assert lines == [
        "no configuration of do-build-wall found before the search was stopped:",
        "  one may exist (a longer --time-limit may find it)",
    ]
    assert explanation(search.report)["complete"] is False


def test_configurations_found_before_the_limit_are_proven() -> None:
    p = load(ROOT / "domains/build-wall/domain.lisp", ROOT / "domains/build-wall/state-6.4.lisp")
    configs, search = plan(p.task, p.goal_call, limit=3)
    assert [c.proven for c in configs] == [True, True, True]
    assert not search.status.stopped


def test_cli_time_limit_json(tmp_path: Path) -> None:
    d, s = big(tmp_path)
    out = subprocess.run(
        [
            sys.executable,
            "-m",
            "cfgplan",
            "plan",
            str(d),
            str(s),
            "--all",
            "--time-limit",
            "0",
            "--format",
            "json",
        ],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=120,
    )
    assert out.returncode == 0, out.stderr
    doc = json.loads(out.stdout)
    assert doc["stats"]["stopped"] == "time limit"
    assert [c["proven"] for c in doc["configurations"]] == [False]
    assert "search stopped (time limit)" in out.stderr


def _default_sigint() -> None:
    signal.signal(signal.SIGINT, signal.SIG_DFL)


@pytest.mark.slow
def test_ctrl_c_returns_what_was_found(tmp_path: Path) -> None:
    """Listing every configuration of a huge instance never ends: after the
    progress line appears, Ctrl-C (SIGINT) stops it and the answer so far is printed."""
    d, s = big(tmp_path)
    proc = subprocess.Popen(
        [sys.executable, "-m", "cfgplan", "plan", str(d), str(s), "--all", "--format", "json"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=ROOT,
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
        # Python makes Ctrl-C a KeyboardInterrupt only where SIGINT is not ignored
        # when it starts, and a test run started in the background ignores it.
        preexec_fn=_default_sigint,
    )
    assert proc.stderr is not None
    deadline = time.monotonic() + 60
    line = ""
    while time.monotonic() < deadline:
        line = proc.stderr.readline()
        if line.startswith("planning..."):
            break
    assert line.startswith("planning..."), "no progress line on stderr"
    proc.send_signal(signal.SIGINT)
    stdout, stderr = proc.communicate(timeout=60)
    assert proc.returncode == 0, stderr
    doc = json.loads(stdout)
    assert doc["stats"]["stopped"] == "interrupted"
    assert doc["configurations"], "nothing reported after Ctrl-C"
    assert "search stopped (interrupted)" in stderr
