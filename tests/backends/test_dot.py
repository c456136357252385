"""DOT diagrams of configurations (Fig. 4.3, 6.8, 6.11) and of the method
hierarchy (Fig. 4.4): golden files and structure.

The golden files in tests/golden/ were made by the code and checked by eye
against the figures; ``CFGPLAN_UPDATE_GOLDEN=1 pytest tests/backends`` rewrites
them. Each test names the figure it mirrors.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest
from typer.testing import CliRunner

import cfgplan.cli.render  # noqa: F401  (loads the command module)
from cfgplan.backends.dot import (
    GLOBAL_EDGE,
    LOCAL_EDGE,
    configuration_dot,
    layers,
    robot_colours,
    robot_order,
)
from cfgplan.backends.dot_hierarchy import hierarchy_dot
from cfgplan.cli.app import app
from cfgplan.configuration.model import Configuration
from cfgplan.diagnostics import CfgplanError
from cfgplan.notation import call_text
from cfgplan.planner import plan
from cfgplan.problem import Problem, load

ROOT = Path(__file__).resolve().parents[2]
GOLDEN = ROOT / "tests" / "golden"
UPDATE = os.environ.get("CFGPLAN_UPDATE_GOLDEN", "") not in ("", "0")

CROSS = ("domains/cross-door/domain.lisp", "domains/cross-door/state-6.2.2-step1.lisp")
CARRY = ("domains/carry-bar/domain.lisp", "domains/carry-bar/state-6.3.2.lisp")
WALL = ("domains/build-wall/domain.lisp", "domains/build-wall/state-6.4.lisp")

RECURSIVE_DOMAIN = """
(make-functionality :name '(sense ?r) :out '((data ?r)))
(make-functionality :name '(act ?r) :in '((data ?r)))
(make-config-method :name '(relay ?r)
  :precond '((robot ?r))
  :out '((?f1 (data ?r)))
  :body '((?f1 (sense ?r))))
(make-config-method :name '(relay ?r)
  :precond '((robot ?r) (robot ?o))
  :out '((?f1 (data ?o)))
  :body '((?f1 (relay ?o))))
(make-config-method :name '(top ?r)
  :channels '(((local ?r) ?f1 ?f2 (data ?r)))
  :body '((?f1 (relay ?r)) (?f2 (act ?r))))
"""


def planned(paths: tuple[str, str], rank: int = 1) -> tuple[Problem, Configuration]:
    problem = load(ROOT / paths[0], ROOT / paths[1])
    configs, _ = plan(problem.task, problem.goal_call, limit=rank)
    assert len(configs) >= rank
    return problem, configs[rank - 1]


def cli_dot(tmp_path: Path, *args: str) -> str:
    """``cfgplan render ARGS -o tmp/out.dot``, run in-process; the DOT it wrote."""
    out = tmp_path / "out.dot"
    result = CliRunner().invoke(app, ["render", *args, "-o", str(out)])
    assert result.exit_code == 0, result.output
    return out.read_text(encoding="utf-8")


def check_golden(name: str, text: str) -> None:
    """``text`` equals tests/golden/NAME byte for byte (rewritten when UPDATE)."""
    path = GOLDEN / name
    if UPDATE:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")
        return
    assert path.exists(), f"missing {path}; make it with CFGPLAN_UPDATE_GOLDEN=1"
    assert text == path.read_text(encoding="utf-8"), (
        f"DOT differs from {path}; if the change is intended, rerun with "
        "CFGPLAN_UPDATE_GOLDEN=1 and check the picture by eye"
    )


def nodes(dot: str) -> dict[str, str]:
    """Node id -> its attribute text, for the F-labelled functionality boxes."""
    return dict(re.findall(r"^\t+(F\d+) \[(.*)\]$", dot, re.M))


def edges(dot: str) -> list[tuple[str, str, str]]:
    """(tail, head, attributes) of the visible edges between functionalities."""
    found = re.findall(r"^\t+(F\d+) -> (F\d+) \[(.*)\]$", dot, re.M)
    return [e for e in found if "style=invis" not in e[2]]


def clusters(dot: str) -> dict[str, str]:
    """Cluster name -> the text of its block."""
    return dict(re.findall(r"^\tsubgraph (cluster_\w+) \{\n(.*?)^\t\}$", dot, re.M | re.S))


# -- golden files -------------------------------------------------------------------


def test_golden_cross_door_44(tmp_path: Path) -> None:
    """Fig. 4.3 (and Fig. 6.4 top): Pippi crosses with door data from Emil, cost 44."""
    dot = cli_dot(tmp_path, *CROSS, "--rank", "1")
    assert "cost 44" in dot
    check_golden("config-cross-door-44.dot", dot)


def test_golden_carry_bar_33(tmp_path: Path) -> None:
    """Fig. 6.8 top: Emil measures angle and distance to Pippi with the laser, cost 33."""
    dot = cli_dot(tmp_path, *CARRY)
    assert "cost 33" in dot
    check_golden("config-carry-bar-33.dot", dot)


def test_golden_build_wall_53(tmp_path: Path) -> None:
    """Fig. 6.11: two robots push block B1 to wall W1, Emil's laser measures, cost 53."""
    dot = cli_dot(tmp_path, *WALL)
    assert "cost 53" in dot
    check_golden("config-build-wall-53.dot", dot)


def test_golden_cross_door_hierarchy(tmp_path: Path) -> None:
    """Fig. 4.4: the hierarchy of methods (grey) and functionalities (white) for cross-door."""
    dot = cli_dot(tmp_path, *CROSS, "--hierarchy")
    check_golden("hierarchy-cross-door.dot", dot)


# -- configuration structure --------------------------------------------------------


@pytest.mark.parametrize("paths", [CROSS, CARRY, WALL], ids=["fig4.3", "fig6.8", "fig6.11"])
def test_every_functionality_is_a_box_in_its_robots_cluster(paths: tuple[str, str]) -> None:
    """Fig. 4.3 / 6.11: one box per functionality, coloured by its robot (one
    colour and one cluster per robot), showing its name and ``label : (args)``
    in the case they were written (names are case-sensitive)."""
    problem, config = planned(paths)
    dot = configuration_dot(config, first=problem.goal_call[1:])
    boxes = nodes(dot)
    assert set(boxes) == {f.label for f in config.functionalities}
    robots = robot_order(config, problem.goal_call[1:])
    colours = robot_colours(robots)
    assert len(set(colours.values())) == len(robots)
    blocks = clusters(dot)
    assert len(blocks) == len(robots) + 1  # one per robot, and the legend
    for index, robot in enumerate(robots):
        block = blocks[f"cluster_{index}_{robot}"]
        assert f"label={robot} " in block
        inside = set(re.findall(r"^\t\t(F\d+) \[", block, re.M))
        assert inside == {f.label for f in config.functionalities if f.robot == robot}
        assert f"fillcolor={colours[robot]}]" in blocks["cluster_legend"]
    for f in config.functionalities:
        attrs = boxes[f.label]
        assert f"<B>{f.name}</B>" in attrs
        assert f"{f.label} : ({' '.join(f.args)})" in attrs
        assert f"fillcolor={colours[f.robot]}" in attrs


@pytest.mark.parametrize("paths", [CROSS, CARRY, WALL], ids=["fig4.3", "fig6.8", "fig6.11"])
def test_global_channels_bold_black_local_thin_grey(paths: tuple[str, str]) -> None:
    """Captions of Fig. 4.3 and 6.11: global channels are black bold arrows,
    local channels grey thin ones; one arrow per channel, labelled with its data."""
    _, config = planned(paths)
    dot = configuration_dot(config)
    drawn = edges(dot)
    assert len(drawn) == len(config.channels)
    unmatched = list(drawn)
    for ch in config.channels:
        data = f"{ch.data[0]}({', '.join(ch.data[1:])})"
        style = GLOBAL_EDGE if ch.kind == "global" else LOCAL_EDGE
        match = [
            e
            for e in unmatched
            if (e[0], e[1]) == (ch.source, ch.target)
            and f'label="{data}' in e[2]
            and all(f"{key}={value}" in e[2] for key, value in style.items())
        ]
        assert match, f"no arrow for {ch}"
        unmatched.remove(match[0])


@pytest.mark.parametrize("paths", [CROSS, CARRY, WALL], ids=["fig4.3", "fig6.8", "fig6.11"])
def test_local_channels_are_drawn_inside_their_robots_cluster(paths: tuple[str, str]) -> None:
    """A local channel's arrow, and so its label, belongs to its
    robot's cluster; a global channel's arrow to no cluster."""
    problem, config = planned(paths)
    dot = configuration_dot(config, first=problem.goal_call[1:])
    robots = robot_order(config, problem.goal_call[1:])
    blocks = clusters(dot)
    outside = dot
    for block in blocks.values():
        outside = outside.replace(block, "")
    for index, robot in enumerate(robots):
        inside = edges(blocks[f"cluster_{index}_{robot}"])
        mine = [c for c in config.channels if c.kind == "local" and c.source_robot == robot]
        assert sorted((t, h) for t, h, _ in inside) == sorted((c.source, c.target) for c in mine)
    globals_ = [c for c in config.channels if c.kind == "global"]
    assert sorted((t, h) for t, h, _ in edges(outside)) == sorted(
        (c.source, c.target) for c in globals_
    )
    assert globals_ and len(globals_) < len(config.channels)  # both kinds are drawn


def test_cross_door_44_counts_and_colours() -> None:
    """Fig. 4.3: 8 boxes, 3 bold and 7 thin arrows; Pippi white, Emil grey."""
    problem, config = planned(CROSS)
    dot = configuration_dot(config, first=problem.goal_call[1:])
    drawn = edges(dot)
    assert len(nodes(dot)) == 8
    assert sum("style=bold" in a for _, _, a in drawn) == 3
    assert sum("style=solid" in a for _, _, a in drawn) == 7
    assert robot_colours(robot_order(config, ["Pippi"])) == {"Pippi": "white", "Emil": "gray80"}


def test_sensors_on_top_cross_door_at_the_bottom() -> None:
    """Fig. 4.3: the compasses and the camera head the drawing, cross-door ends it."""
    _, config = planned(CROSS)
    layer = layers(config)
    by_name = {f.name: layer[f.label] for f in config.functionalities}
    assert by_name["camera"] == by_name["compass"] == 0
    assert by_name["transform-info"] == 2
    assert by_name["cross-door"] == 3
    dot = configuration_dot(config)
    label = {call_text((f.name, *f.args)): f.label for f in config.functionalities}
    keep = re.findall(r"^\t\t(F\d+) -> (F\d+) \[minlen=(\d+) style=invis weight=0\]", dot, re.M)
    # Pippi's compass three layers above her cross-door, not beside it
    assert (label["compass(Pippi)"], label["cross-door(Pippi, Door1)"], "3") in keep


def test_bandwidth_is_shown_with_the_data() -> None:
    """Section 4.6: global channels declared with a bandwidth show it."""
    problem = load(
        ROOT / "domains/cross-door/domain-bandwidth.lisp",
        ROOT / "domains/cross-door/state-4.6-media.lisp",
    )
    configs, _ = plan(problem.task, problem.goal_call, limit=1)
    dot = configuration_dot(configs[0])
    assert 'label="pos(Pippi, Door1)\\nbandwidth 20"' in dot
    assert 'label="orient(Pippi, Door1)\\nbandwidth 10"' in dot


@pytest.mark.slow
def test_dot_is_deterministic_across_hash_seeds(tmp_path: Path) -> None:
    """The same input gives the same bytes, whatever the hash seed."""
    code = "import cfgplan.cli.render; from cfgplan.cli.app import main; main()"
    texts = []
    for seed in ("1", "987"):
        for extra in ((), ("--hierarchy",)):
            out = tmp_path / f"{seed}{len(extra)}.dot"
            done = subprocess.run(
                [sys.executable, "-c", code, "render", *WALL, *extra, "-o", str(out)],
                cwd=ROOT,
                capture_output=True,
                text=True,
                env={**os.environ, "PYTHONHASHSEED": seed},
                timeout=120,
                check=False,
            )
            assert done.returncode == 0, done.stderr
            texts.append(out.read_bytes())
    assert texts[0] == texts[2] and texts[1] == texts[3]


# -- hierarchy ----------------------------------------------------------------------


def test_hierarchy_of_cross_door_is_fig_4_4() -> None:
    """Fig. 4.4: do-cross-door(r, d) -> get-door-info(rh1, r, d) -> ..., methods grey,
    functionalities white; the figure's boxes are all there (the thesis writes rh)."""
    problem, _ = planned(CROSS)
    dot = hierarchy_dot(problem.task, problem.goal_call)
    shown = re.findall(r'^\t"?([\w.]+)"? \[label="([^"]+)" fillcolor=(\w+)', dot, re.M)
    grey = {label for _, label, colour in shown if colour == "gray80"}
    white = {label for _, label, colour in shown if colour == "white"}
    assert {
        "do-cross-door(r, d)",
        "get-door-info(rh1, r, d)",
        "get-door-info(rh1, d)",
        "get-robot-orient(rh1, r)",
        "get-robot-pos(rh1, r)",
    } <= grey
    assert {
        "cross-door(r, d)",
        "transform-info(rh1, r, d)",
        "measure-robot-pos(rh1, r)",
        "camera(rh1)",
        "measure-door(rh1, d)",
        "measure-robot-orient-compass(rh1, r)",
        "compass(rh1)",
        "compass(r)",
    } <= white
    ids = {node_id: label for node_id, label, _ in shown}
    assert ids["goal"] == "do-cross-door(r, d)"
    assert ids["goal.f1"] == "get-door-info(rh1, r, d)"
    assert ids["goal.f1.f1.f1"] == "camera(rh1)"  # under get-door-info(rh1, d)
    assert ids["goal.f1.f3.f1"] == "camera(rh1)"  # and again under get-robot-pos
    assert '\tgoal -> "goal.f1"\n' in dot and '\tgoal -> "goal.f2"\n' in dot


def test_hierarchy_shows_each_version_of_a_method() -> None:
    """Section 4.5: get-robot-orient has two versions (compasses, cameras); each gets
    a version node with its preconditions, and its own body below it."""
    problem, _ = planned(CROSS)
    dot = hierarchy_dot(problem.task, problem.goal_call)
    assert '"goal.f1.f2.v1" [label=<version 1<BR/>compass(rh1)<BR/>compass(r)>' in dot
    assert '"goal.f1.f2.v2" [label=<version 2<BR/>camera(r)<BR/>camera(rh1)>' in dot
    assert '"goal.f1.f2.v1" -> "goal.f1.f2.v1.f3"' in dot  # measure-robot-orient-compass
    assert '"goal.f1.f2.v2" -> "goal.f1.f2.v2.f1"' in dot  # get-robot-angle(rh1, r)
    assert "goal.f1.v" not in dot  # get-door-info(rh1, r, d) has a single version


def test_recursive_method_ends(tmp_path: Path) -> None:
    """A method that calls itself is drawn once, with a dashed arrow back."""
    domain = tmp_path / "domain.lisp"
    domain.write_text(RECURSIVE_DOMAIN, encoding="utf-8")
    state = tmp_path / "state.lisp"
    state.write_text("(state robot(A), robot(B))\n(goal (top A))\n", encoding="utf-8")
    problem = load(domain, state)
    dot = hierarchy_dot(problem.task, problem.goal_call)
    assert '"goal.f1.v2.f1" [label="relay(o)\\n(recursive)"' in dot
    assert '"goal.f1.v2.f1" -> "goal.f1" [label=recurs constraint=false style=dashed]' in dot
    assert dot.count("relay(") == 2


def test_hierarchy_draws_a_method_call_once() -> None:
    """Build-wall's hierarchy uses get-block-data(robserv, b, w) under
    all four versions of do-push; it is drawn once, and each caller points to
    it, so the picture stays readable. Functionalities stay leaves under each
    method that uses them, as in Fig. 4.4."""
    problem, _ = planned(WALL)
    dot = hierarchy_dot(problem.task, problem.goal_call)
    grey = re.findall(r'^\t"?([\w.]+)"? \[label="([^"]+)" fillcolor=gray80', dot, re.M)
    labels = [label for _, label in grey]
    assert len(labels) == len(set(labels))  # no method call twice
    block_data = [node for node, label in grey if label == "get-block-data(robserv, b, w)"]
    assert len(block_data) == 1
    callers = re.findall(rf'^\t"?([\w.]+)"? -> "{re.escape(block_data[0])}"$', dot, re.M)
    assert len(callers) == 4  # version 1 and 2 of do-push(rleft, ...) and (rright, ...)
    assert dot.count('[label="laser(robserv)"') == 4  # a leaf under each method using it
    assert len(re.findall(r"^\t\S+ \[label=", dot, re.M)) <= 60  # 130 drawn as a tree


def test_hierarchy_too_large_is_an_error() -> None:
    problem, _ = planned(WALL)
    with pytest.raises(CfgplanError, match="more than 10 nodes"):
        hierarchy_dot(problem.task, problem.goal_call, max_nodes=10)


def test_hierarchy_of_a_functionality_is_an_error() -> None:
    problem, _ = planned(CROSS)
    with pytest.raises(CfgplanError, match="not a method"):
        hierarchy_dot(problem.task, ("camera", "Emil"))
