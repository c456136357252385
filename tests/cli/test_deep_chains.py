"""Deep method chains: no stage recurses on the depth of the input.

``(top ?r)`` expands through ``m0 -> m1 -> ... -> m{n-1} -> (sense ?r)``: the
configuration is two functionalities, but the method hierarchy is ``n`` levels
deep. The issue found 330 levels enough to make ``plan``, ``emit`` and ``run``
die with RecursionError in ``planner/bound.py`` and about 500 to do it in
``render --hierarchy``. Every command is run on such a chain (the planner's
bound summarises without recursion).
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from benchmarks.fuzz_inputs import chain

ROOT = Path(__file__).resolve().parents[2]

IMPL = """\
from cfgplan.runtime import functionality


@functionality("sense")
def sense() -> int:
    return 7


@functionality("act")
def act(data: int) -> None:
    print("act received", data)
"""


@pytest.fixture
def files(tmp_path: Path) -> dict[str, str]:
    for levels in (330, 1500):
        (tmp_path / f"chain-{levels}.lisp").write_bytes(chain(levels))
    (tmp_path / "state.lisp").write_text("(state (robot Pippi))\n(goal (top Pippi))\n")
    (tmp_path / "impl.py").write_text(IMPL)
    return {
        "330": str(tmp_path / "chain-330.lisp"),
        "1500": str(tmp_path / "chain-1500.lisp"),
        "state": str(tmp_path / "state.lisp"),
        "impl": str(tmp_path / "impl.py"),
        "out": str(tmp_path / "out"),
    }


def run(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "cfgplan", *args],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=300,
    )


def ok(done: subprocess.CompletedProcess[str]) -> str:
    assert "Traceback" not in done.stderr, done.stderr[-2000:]
    assert done.returncode == 0, done.stderr[-2000:]
    return done.stdout


@pytest.mark.parametrize("levels", ["330", pytest.param("1500", marks=pytest.mark.slow)])
def test_check(files: dict[str, str], levels: str) -> None:
    out = ok(run("check", files[levels], files["state"]))
    assert f"{int(levels) + 1} methods" in out


@pytest.mark.slow
@pytest.mark.parametrize("levels", ["330", "1500"])
def test_render_hierarchy(files: dict[str, str], levels: str) -> None:
    output = Path(files["out"] + ".dot")
    ok(run("render", files[levels], files["state"], "--hierarchy", "-o", str(output)))
    dot = output.read_text()
    assert f'"goal.f1{".f1" * int(levels)}" [label="sense(r)"' in dot  # the bottom of the chain


def test_plan(files: dict[str, str]) -> None:
    out = ok(run("plan", files["330"], files["state"], "--format", "lisp"))
    assert "sense(Pippi)" in out and "act(Pippi)" in out


@pytest.mark.slow  # check and plan of the deep chain stay in the fast loop
@pytest.mark.parametrize("lang", ["lisp", "python"])
def test_emit(files: dict[str, str], lang: str) -> None:
    ok(run("emit", files["330"], files["state"], "--lang", lang, "-o", files["out"]))
    assert (Path(files["out"]) / "configuration.txt").exists()


@pytest.mark.slow
def test_run(files: dict[str, str]) -> None:
    out = ok(run("run", files["330"], files["state"], "--impl", files["impl"], "--cycles", "2"))
    assert "act" in out


@pytest.mark.slow
def test_render(files: dict[str, str]) -> None:
    output = Path(files["out"] + ".dot")
    ok(run("render", files["330"], files["state"], "-o", str(output)))
    assert "<B>sense</B>" in output.read_text()
