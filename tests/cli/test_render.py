"""``cfgplan render``: formats from the suffix, --rank, --goal, --weights,
--hierarchy, --force, exit codes (Fig. 4.3, 4.4 as SVG and PNG)."""

from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

import cfgplan.cli.render  # noqa: F401  (loads the command module)
from cfgplan.backends import render as engine
from cfgplan.cli.app import app
from cfgplan.planner import plan
from cfgplan.problem import load
from tests.backends.test_render import PNG_MAGIC, svg_texts

ROOT = Path(__file__).resolve().parents[2]
CROSS = ("domains/cross-door/domain.lisp", "domains/cross-door/state-6.2.2-step1.lisp")


def invoke(*args: str) -> tuple[int, str]:
    result = CliRunner().invoke(app, ["render", *args])
    return result.exit_code, result.output


def test_missing_engine_cli_still_writes_dot(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    monkeypatch.setattr(engine, "load_pygraphviz", lambda: None)
    monkeypatch.setattr(engine, "system_dot", lambda: None)
    code, output = invoke(*CROSS, "-o", str(tmp_path / "x.svg"))
    assert code == 1 and "no Graphviz layout engine" in output
    assert not (tmp_path / "x.svg").exists()
    code, _ = invoke(*CROSS, "-o", str(tmp_path / "x.dot"))
    assert code == 0 and (tmp_path / "x.dot").read_text().startswith("digraph configuration {")


def test_cli_svg_shows_every_functionality(tmp_path: Path) -> None:
    """Fig. 4.3 as SVG: every box's name and ``label : (args)``, case kept, is in the picture."""
    out = tmp_path / "cross-door.svg"
    code, output = invoke(*CROSS, "-o", str(out))
    assert code == 0, output
    texts = svg_texts(out.read_bytes())
    problem = load(ROOT / CROSS[0], ROOT / CROSS[1])
    (config,), _ = plan(problem.task, problem.goal_call, limit=1)
    for f in config.functionalities:
        assert f.name in texts
        assert f"{f.label} : ({' '.join(f.args)})" in texts
    for ch in config.channels:
        assert f"{ch.data[0]}({', '.join(ch.data[1:])})" in texts
    assert {"Pippi", "Emil", "Legend", "global channel", "local channel"} <= set(texts)


def test_cli_png(tmp_path: Path) -> None:
    out = tmp_path / "cross-door.PNG"
    code, output = invoke(*CROSS, "-o", str(out))
    assert code == 0, output
    assert out.read_bytes().startswith(PNG_MAGIC)


def test_cli_hierarchy_svg(tmp_path: Path) -> None:
    """Fig. 4.4 as SVG."""
    out = tmp_path / "hierarchy.svg"
    code, output = invoke(*CROSS, "--hierarchy", "-o", str(out))
    assert code == 0, output
    texts = svg_texts(out.read_bytes())
    assert {"do-cross-door(r, d)", "get-door-info(rh1, r, d)", "compass(rh1)"} <= set(texts)
    assert "version 2" in texts


def test_cli_rank_and_goal(tmp_path: Path) -> None:
    """Section 6.2.2: the second configuration costs 47; --goal swaps the roles."""
    out = tmp_path / "r2.dot"
    code, output = invoke(*CROSS, "--rank", "2", "-o", str(out))
    assert code == 0, output
    assert "rank 2, cost 47" in out.read_text()
    out = tmp_path / "emil.dot"
    code, output = invoke(*CROSS, "--goal", "(do-cross-door Emil Door1)", "-o", str(out))
    assert code == 0, output
    dot = out.read_text()
    assert "do-cross-door(Emil, Door1): rank 1, cost 44" in dot
    assert "legend_robot_0 [label=Emil fillcolor=white]" in dot  # the goal's robot is white


def test_cli_rank_too_high_exits_3(tmp_path: Path) -> None:
    code, output = invoke(*CROSS, "--rank", "9", "-o", str(tmp_path / "x.dot"))
    assert code == 3
    assert "none of rank 9" in output
    assert not (tmp_path / "x.dot").exists()


def test_cli_unknown_suffix_is_a_usage_error(tmp_path: Path) -> None:
    code, output = invoke(*CROSS, "-o", str(tmp_path / "x.pdf"))
    assert code == 2
    assert ".dot, .svg, .png" in output


def test_cli_never_overwrites_without_force(tmp_path: Path) -> None:
    out = tmp_path / "x.dot"
    out.write_text("keep me", encoding="utf-8")
    code, output = invoke(*CROSS, "-o", str(out))
    assert code == 1
    assert "exists; pass --force" in output
    assert out.read_text(encoding="utf-8") == "keep me"
    code, output = invoke(*CROSS, "-o", str(out), "--force")
    assert code == 0, output
    assert out.read_text(encoding="utf-8").startswith("digraph configuration {")


def test_cli_weights_change_the_cost(tmp_path: Path) -> None:
    out = tmp_path / "w.dot"
    code, output = invoke(*CROSS, "--weights", "robot=0", "-o", str(out))
    assert code == 0, output
    assert "rank 1, cost 24" in out.read_text()


def test_cli_invalid_input_exits_1(tmp_path: Path) -> None:
    bad = tmp_path / "bad.lisp"
    bad.write_text("(make-functionality :name", encoding="utf-8")
    code, output = invoke(str(bad), CROSS[1], "-o", str(tmp_path / "x.dot"))
    assert code == 1
    assert "bad.lisp:1:" in output
