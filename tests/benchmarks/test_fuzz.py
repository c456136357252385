"""The end-to-end fuzzer (benchmarks/fuzz.py) at a small budget, and its own parts.

A few hundred inputs run here on every test run; ``python -m benchmarks.fuzz
--inputs 100000`` is the big budget (README, "Fuzzing"). The harness is
checked too: that it tells a traceback, a hang, a crash and a file written
outside ``-o`` from a clean error.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import pytest

from benchmarks import fuzz, fuzz_worker
from benchmarks.fuzz_inputs import Case, chain

CROSS = Path(__file__).resolve().parents[2] / "domains" / "cross-door"


@pytest.mark.slow
def test_a_small_budget_finds_nothing_outside_the_planner(tmp_path: Path) -> None:
    tally = fuzz.campaign(200, seed=0, time_limit=5.0, memory_mib=2048, save=tmp_path)
    assert sum(tally.inputs.values()) == 200
    assert tally.inputs["success"] > 0 and tally.inputs["clean"] > 0
    assert tally.commands["emit-python"]["success"] > 0  # the backends were reached
    # Recursion in planner/bound.py is the issue-8 rewrite's (deep chains).
    others = [
        (f.kind, f.command, f.where, f.detail[-300:])
        for f in tally.findings
        if f.where != "planner"
    ]
    assert others == []
    assert tally.commands["check"]["timeout"] == 0


def test_the_harness_tells_a_hang_and_a_crash(tmp_path: Path) -> None:
    deep = Case("chains", chain(300), b"(state (robot Pippi))\n(goal (top Pippi))\n")
    hurried = fuzz.Worker(time_limit=0.05, memory_mib=2048, folder=tmp_path)
    try:
        results, _ = hurried.run(deep)  # reading 300 methods takes far more than 50 ms
    finally:
        hurried.stop()
    kind, detail = results["check"]
    assert kind == "timeout"
    assert "most recent call first" in detail  # the stack of the hang, dumped
    starved = fuzz.Worker(time_limit=5.0, memory_mib=8, folder=tmp_path)
    try:
        results, _ = starved.run(deep)  # 8 MiB: Python cannot even start
    finally:
        starved.stop()
    assert [kind for kind, _ in results.values()] == ["crash"]


def test_the_harness_tells_a_traceback_from_a_clean_error(monkeypatch: pytest.MonkeyPatch) -> None:
    import cfgplan.cli.app

    def broken() -> None:
        raise KeyError("a bug")

    assert fuzz_worker._run_cli(["check", "/nonexistent"])[0] == "clean"
    monkeypatch.setattr(cfgplan.cli.app, "main", broken)
    kind, detail = fuzz_worker._run_cli(["check", str(CROSS / "domain.lisp")])
    assert kind == "traceback" and "KeyError: 'a bug'" in detail


def test_a_file_outside_the_output_folder_is_an_escape(tmp_path: Path) -> None:
    (tmp_path / "a" / "b" / "out").mkdir(parents=True)
    (tmp_path / "a" / "b" / "out" / "emil.py").write_text("")
    assert fuzz_worker._check_outputs("emit-python", tmp_path) is None
    (tmp_path / "a" / "escaped.py").write_text("")
    found = fuzz_worker._check_outputs("emit-python", tmp_path)
    assert found is not None and found[0] == "escape"


def test_a_temporary_folder_named_like_the_bait_is_no_escape(tmp_path: Path) -> None:
    """The big run once counted a worker's own temporary folder,
    /tmp/cfgplan-fuzz-abs21csp, as a file written by cfgplan."""
    with tempfile.TemporaryDirectory(prefix=Path(fuzz_worker.ABSOLUTE_BAIT).name, dir="/tmp"):
        assert fuzz_worker._check_outputs("check", tmp_path) is None


def test_where_names_the_innermost_cfgplan_package() -> None:
    traceback = (
        "Traceback (most recent call last):\n"
        '  File "/x/cfgplan/cli/app.py", line 1, in main\n'
        '  File "/x/cfgplan/planner/bound.py", line 2, in _summarise\n'
        "RecursionError: maximum recursion depth exceeded\n"
    )
    assert fuzz.where(traceback) == "planner"
    dump = (
        "Thread 0x1 (most recent call first):\n"
        '  File "/x/cfgplan/syntax/reader.py", line 3 in parse\n'
        '  File "/x/cfgplan/cli/app.py", line 1 in main\n'
    )
    assert fuzz.where(dump) == "syntax"
    assert fuzz.where("no frames") == "?"
