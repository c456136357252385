"""The Python translation (5.3 with cfgplan.runtime): golden files, and the emitted
code of the cost-44 configuration (4.6) run end to end on the example geometry."""

from __future__ import annotations

import math
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest

from cfgplan.backends.python import module_name, run_all, to_python
from cfgplan.backends.wiring import RobotPart, deploy
from cfgplan.configuration.model import Configuration
from cfgplan.planner import plan
from cfgplan.problem import Problem, load
from cfgplan.runtime import Registry, assemble, load_module
from cfgplan.security.identity import problem_id
from tests.backends.support import (
    CARRY,
    CROSS,
    EXAMPLE_IMPL,
    ROOT,
    carry_bar_33,
    check_golden,
    cross_door_44,
)

Planned = Callable[[], tuple[Problem, Configuration]]
TITLE = "Configuration rank 1, cost {cost}, for {goal}"


def _emit(parts: tuple[RobotPart, ...], title: str, where: Path) -> None:
    for part in parts:
        (where / f"{module_name(part.robot)}.py").write_text(to_python(part, title))
    (where / "run_all.py").write_text(run_all(parts, title))


@pytest.mark.parametrize(
    ("case", "planned", "goal", "files"),
    [
        ("cross-door-44", cross_door_44, "do-cross-door(Pippi, Door1)", CROSS),
        ("carry-bar-33", carry_bar_33, "do-carry-bar(Pippi)", CARRY),
    ],
)
def test_golden(case: str, planned: Planned, goal: str, files: tuple[str, str]) -> None:
    """One module per robot and run_all.py; each compiles and stays within 100 columns;
    each robot announces the problem it was planned for (PROBLEM, the
    fingerprint of the domain, the state and the goal)."""
    problem, config = planned()
    parts = deploy(config, problem.domain)
    title = TITLE.format(cost=int(config.cost), goal=goal)
    identity = problem_id(problem, *files)
    texts = {f"{module_name(p.robot)}.py": to_python(p, title, identity) for p in parts}
    texts["run_all.py"] = run_all(parts, title)
    assert list(texts) == ["pippi.py", "emil.py", "run_all.py"]
    for name, text in texts.items():
        compile(text, name, "exec")
        assert max(len(line) for line in text.splitlines()) <= 100
        check_golden(f"{case}/{name}", text)


def test_emil_calls_follow_5_4() -> None:
    """The same calls as the LAMBDA of 5.4, written for cfgplan.runtime."""
    problem, config = cross_door_44()
    _, emil = deploy(config, problem.domain)
    text = to_python(emil, "t")
    calls = [line.strip() for line in text.splitlines() if "(inputs=" in line]
    assert [c.split("(")[0].split("_", 1)[1] for c in calls] == [
        "compass",
        "camera",
        "measure_robot_pos",
        "measure_robot_orient_compass",
        "measure_door",
        "transform_info",
    ]
    assert calls[3].endswith("(inputs=[ch_3, ch_2], outputs=[[ch_7]])")
    assert calls[5].endswith("(inputs=[ch_7, ch_8, ch_6, ch_5], outputs=[[ch_10], [ch_9]])")


def _expected_door_relative_to_pippi() -> tuple[tuple[float, float], float]:
    """Independently of the implementations: Door1's pose in Pippi's frame."""
    world = load_module(EXAMPLE_IMPL).WORLD
    px, py, ph = world["Pippi"]
    dx, dy, dh = world["Door1"]
    c, s = math.cos(ph), math.sin(ph)
    pos = (c * (dx - px) + s * (dy - py), -s * (dx - px) + c * (dy - py))
    orient = (dh - ph + math.pi) % (2 * math.pi) - math.pi
    return pos, orient


def test_emitted_cross_door_44_runs_and_pippi_receives_the_door(tmp_path: Path) -> None:
    """Emil's camera and both compasses, through transform-info and two global
    channels, give Pippi's cross-door the door relative to herself."""
    problem, config = cross_door_44()
    _emit(deploy(config, problem.domain), "t", tmp_path)
    programs = load_module(tmp_path / "run_all.py").programs()
    society = assemble(programs, Registry.load(EXAMPLE_IMPL))
    society.run(3)
    received = [e for e in society.calls if e.name == "cross-door"]
    assert [e.status for e in received] == ["waiting", "ran", "ran"]
    (pos_data, pos), (orient_data, orient) = received[1].inputs
    assert pos_data == ("pos", "Pippi", "Door1")
    assert orient_data == ("orient", "Pippi", "Door1")
    want_pos, want_orient = _expected_door_relative_to_pippi()
    assert isinstance(pos, list) and isinstance(orient, float)  # JSON: a tuple arrives as a list
    assert pos == pytest.approx(want_pos, abs=1e-9)
    assert orient == pytest.approx(want_orient, abs=1e-9)
    # not a degenerate example: the door is off Pippi's axes and turned
    assert min(abs(want_pos[0]), abs(want_pos[1]), abs(want_orient)) > 0.1


def test_emitted_run_all_as_a_script(tmp_path: Path) -> None:
    problem, config = cross_door_44()
    _emit(deploy(config, problem.domain), "t", tmp_path)
    (pos, orient) = _expected_door_relative_to_pippi()
    (label,) = [f.label for f in config.functionalities if f.name == "cross-door"]
    out = _script(tmp_path / "run_all.py")
    assert out.returncode == 0, out.stderr
    assert (
        f"cycle 2: Pippi {label} cross-door(Pippi, Door1) received pos(Pippi, Door1) = "
        f"[{pos[0]:.3f}, {pos[1]:.3f}], orient(Pippi, Door1) = {orient:.3f}"
    ) in out.stdout.splitlines()


def _script(script: Path, *extra: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [
            sys.executable,
            str(script),
            "--impl",
            str(EXAMPLE_IMPL),
            "--cycles",
            "2",
            "--rate",
            "0",
            *extra,
        ],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=60,
    )


def _alone(script: Path) -> subprocess.CompletedProcess[str]:
    return _script(script, "--transport", "inprocess")


def test_one_robot_alone_reaches_no_other(tmp_path: Path) -> None:
    """python emil.py --transport inprocess: Pippi's compass never arrives, so
    Emil waits for it; pippi.py: its compass readings for Emil are dropped, and
    said so. (Over Zenoh, the default: tests/runtime/test_network.py.)"""
    problem, config = cross_door_44()
    _emit(deploy(config, problem.domain), "t", tmp_path)
    emil = _alone(tmp_path / "emil.py")
    assert emil.returncode == 0, emil.stderr
    assert "measure-robot-orient-compass(Emil, Pippi): ran in 0 of 2 cycles; " in emil.stdout
    assert "waits for global-orient(Pippi)" in emil.stdout
    assert emil.stderr == ""  # Emil sends nothing: transform-info never ran
    pippi = _alone(tmp_path / "pippi.py")
    assert pippi.returncode == 0, pippi.stderr
    assert "compass(Pippi): ran in 2 of 2 cycles" in pippi.stdout
    assert "note: 2 value(s) sent to robots not in this process were dropped" in pippi.stderr


FREQ_DOMAIN = """
(make-functionality :name '(laser ?r) :out '((scan ?r)) :freq 20)
(make-functionality :name '(follow ?r) :in '((scan ?r)) :freq 2.5)
(make-functionality :name '(log ?r) :in '((scan ?r)))
(make-config-method :name '(do-follow ?r)
  :channels '(((local ?r) ?f1 ?f2 (scan ?r)) ((local ?r) ?f1 ?f3 (scan ?r)))
  :body '((?f1 (laser ?r)) (?f2 (follow ?r)) (?f3 (log ?r))))
"""


def test_a_freq_of_the_domain_reaches_the_emitted_wrapper(tmp_path: Path) -> None:
    """3.2: Freq. The emitted code passes it on; the runtime runs at it."""
    (tmp_path / "domain.lisp").write_text(FREQ_DOMAIN)
    (tmp_path / "state.lisp").write_text("(state (robot Ada)) (goal (do-follow Ada))")
    problem = load(tmp_path / "domain.lisp", tmp_path / "state.lisp")
    configs, _ = plan(problem.task, problem.goal_call, limit=1)
    (part,) = deploy(configs[0], problem.domain)
    text = to_python(part, "t")
    compile(text, "ada.py", "exec")
    wrappers = [line.strip() for line in text.splitlines() if "= robot.wrapper(" in line]
    assert [w.split("robot.wrapper")[1] for w in wrappers] == [
        '("F2", "laser", freq=20, inputs=0)',
        '("F4", "log", inputs=1)',
        '("F3", "follow", freq=2.5, inputs=1)',
    ]
