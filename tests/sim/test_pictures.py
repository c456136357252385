"""The simulator's pictures, measured: labels that never overlap (as the
renderer reports their extents), marks on the right rows and robots, and the
measures the thesis's experiments are about."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from matplotlib.figure import Figure
from matplotlib.text import Text

from cfgplan.sim.barplot import bar_figure
from cfgplan.sim.geometry import rectangle
from cfgplan.sim.laserview import draw_laser_view, laser_failures
from cfgplan.sim.run import Run
from cfgplan.sim.story import story_of
from cfgplan.sim.timeline import timeline_figure
from cfgplan.sim.trajectories import trajectories_figure

NAMES = ("cross-door", "carry-bar", "build-wall")


def overlaps(fig: Figure) -> list[tuple[str, str]]:
    """Pairs of visible texts of ``fig`` whose extents meet (a pixel's slack)."""
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()  # type: ignore[attr-defined]
    texts = [
        t
        for t in fig.findobj(Text)
        if t.get_visible() and t.get_text().strip() and t.figure is not None
    ]
    boxes = [(t.get_text(), t.get_window_extent(renderer).padded(-1)) for t in texts]
    return [
        (a, b)
        for (a, box_a), (b, box_b) in itertools.combinations(boxes, 2)
        if box_a.width > 0 and box_b.width > 0 and box_a.overlaps(box_b)
    ]


def test_overlaps_sees_two_labels_that_meet() -> None:
    """The check itself: two labels drawn at one place are reported, two apart are not."""
    fig = Figure(figsize=(4, 2))
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    FigureCanvasAgg(fig)
    fig.text(0.1, 0.5, "44: cross-door")
    fig.text(0.15, 0.5, "compass(Emil) fails")
    fig.text(0.1, 0.1, "far away")
    assert overlaps(fig) == [("44: cross-door", "compass(Emil) fails")]


@pytest.mark.slow
@pytest.mark.parametrize("name", NAMES)
def test_no_label_meets_another_in_the_timeline(bundled: dict[str, Run], name: str) -> None:
    """Every text of the timeline (steps, bars, switches, failures, ticks, key):
    no two extents meet; and the timeline has a key line per configuration."""
    fig = timeline_figure(story_of(bundled[name]))
    assert overlaps(fig) == []
    key = [t.get_text() for t in fig.texts if t.get_text().startswith("#")]
    assert len(key) == len(story_of(bundled[name]).configurations())


@pytest.mark.parametrize("name", NAMES)
def test_no_label_meets_another_in_the_trajectories(bundled: dict[str, Run], name: str) -> None:
    """The map's names, the robots', the switches', failures' and steps': no two meet;
    the legend is outside the map."""
    fig = trajectories_figure(bundled[name])
    assert overlaps(fig) == []
    (ax,) = fig.axes
    assert ax.get_legend() is None and len(fig.legends) == 1
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()  # type: ignore[attr-defined]
    legend = fig.legends[0].get_window_extent(renderer)
    assert legend.y1 <= ax.get_window_extent(renderer).y0


def test_the_timeline_numbers_bars_like_the_diagrams(bundled: dict[str, Run]) -> None:
    """Cross-door ran 44 (step 1), 44 (step 2), then 47: bars #1, #2, #3; a
    configuration that ran twice keeps its number."""
    story = story_of(bundled["cross-door"])
    assert [(s.number, s.config.cost) for s in story.spans] == [(1, 44), (2, 44), (3, 47)]
    fig = timeline_figure(story)
    labels = [t.get_text() for t in fig.axes[0].texts]
    assert any(t.startswith("#3 · 47") for t in labels)
    assert [round(m.t, 1) for m in story.of("switch")] == [20.6, 22.6]


def test_a_failure_and_its_recovery_are_on_one_row(bundled: dict[str, Run]) -> None:
    """compass(Emil) fails and works again: both marks on Emil's row, whoever saw them."""
    story = story_of(bundled["cross-door"])
    marks = story.of("failure", "recovery")
    assert [(m.what, m.robot) for m in marks] == [("failure", "Emil"), ("recovery", "Emil")]
    fig = timeline_figure(story)
    ys = {
        line.get_marker(): float(line.get_ydata()[0])  # type: ignore[index]
        for line in fig.axes[0].lines
        if line.get_marker() in ("X", "o")
    }
    assert ys["X"] == ys["o"]


def test_a_switch_star_is_on_the_robot_it_concerns(bundled: dict[str, Run]) -> None:
    """One star per switch, on the robot named by its cause (Emil for 'compass(Emil)
    failed' and for 'next step: do-cross-door(Emil, Door1)'), its label beside it."""
    run = bundled["cross-door"]
    fig = trajectories_figure(run)
    stars = [line for line in fig.axes[0].lines if line.get_marker() == "*"]
    assert len(stars) == len(run.recorder.of("switch")) == 2
    for star, switch in zip(stars, run.recorder.of("switch"), strict=True):
        sample = min(run.world.samples, key=lambda s: abs(s.t - switch.t))
        assert (star.get_xdata()[0], star.get_ydata()[0]) == sample.robots["Emil"][:2]  # type: ignore[index]


def test_carry_bar_plots_the_bar_length_with_its_tolerance(bundled: dict[str, Run]) -> None:
    """The line is the robots' distance at every step; the band is 1.2 ± 0.2 m (6.3)."""
    run = bundled["carry-bar"]
    fig = bar_figure(run)
    assert fig is not None
    ax = fig.axes[0]
    line = next(line for line in ax.lines if "distance" in str(line.get_label()))
    expected = [s.bar for s in run.world.samples if s.bar is not None]
    assert np.allclose(line.get_ydata(), expected)  # type: ignore[arg-type]
    dashed = [line for line in ax.lines if line.get_linestyle() == "--"]
    edges = sorted(round(float(line.get_ydata()[0]), 3) for line in dashed)  # type: ignore[index]
    assert edges == [1.0, 1.4]
    assert min(expected) > 1.0 and max(expected) < 1.4
    assert bar_figure(bundled["cross-door"]) is None


def test_build_wall_shows_what_the_block_hid_from_the_laser(bundled: dict[str, Run]) -> None:
    """At the failure of measure-pos-laser(Emil, W1), B1 hides the end of W1 from
    Emil's laser: hidden points on W1, and the picture says so."""
    run = bundled["build-wall"]
    failures = [(n.t, str(n.record["resource"])) for n in run.recorder.of("failure")]
    assert laser_failures(run.world, failures) == [(failures[0][0], "Emil")]
    fig = Figure()
    ax = fig.add_subplot()
    sample = min(run.world.samples, key=lambda s: abs(s.t - failures[0][0]))
    points, said = draw_laser_view(ax, run.world, sample, "Emil")
    assert said == "B1 hides W1" and len(points) >= 3
    wall = run.world.walls["W1"]
    sides = rectangle(*wall.at, math.radians(wall.heading), *wall.size)
    xs = [c for side in sides for c in side[0::2]]
    ys = [c for side in sides for c in side[1::2]]
    for x, y in points:  # on W1's free end, the side nearest the block (x = 3)
        assert min(ys) - 1e-6 <= y <= max(ys) + 1e-6
        assert x == pytest.approx(min(xs), abs=1e-6)
    texts = [t.get_text() for t in trajectories_figure(run).axes[0].texts]
    assert any(t.startswith("B1 hides W1 from Emil's laser") for t in texts)


def test_the_relay_draws_emils_loss_and_return_on_his_row() -> None:
    """The relay (examples/sim-relay): Emil is lost at 4 s and seen again at 7 s,
    both noticed by Pippi: the cross and the ring on Emil's row; nothing admissible
    in between (no bar); no label meets another in either picture."""
    from cfgplan.sim.run import open_scenario, simulate
    from tests.sim.conftest import ROOT

    run = simulate(open_scenario(str(ROOT / "examples" / "sim-relay" / "relay.toml")))
    story = story_of(run)
    marks = [(m.what, m.robot, m.t) for m in story.of("failure", "recovery")]
    assert marks == [("failure", "Emil", 4.0), ("recovery", "Emil", 7.0)]
    assert [(s.number, s.start, s.end) for s in story.spans] == [
        (1, 0.0, 4.0),
        (1, 7.0, 11.2),
        (2, 11.2, 22.0),
    ]
    assert overlaps(timeline_figure(story)) == []
    assert overlaps(trajectories_figure(run)) == []
