"""What the bundled implementations make of their sensors: a block's centre,
a built wall's free end and when it is hidden, a pose on the map — compared
with the world's truth, which they never read."""

from __future__ import annotations

import math

import pytest

from cfgplan.sim import sensors
from cfgplan.sim.blocks import attach
from cfgplan.sim.geometry import relative, wrap
from cfgplan.sim.perception import block, free_end, localize, square
from cfgplan.sim.run import open_scenario
from cfgplan.sim.world import World


def _build_wall() -> World:
    return World(open_scenario("build-wall").scenario, 1)


def _truth(world: World, robot: str, x: float, y: float) -> tuple[float, float]:
    return relative(world.bodies[robot].pose, x, y)


def test_a_block_is_found_from_behind_and_from_the_side() -> None:
    world = _build_wall()
    b1 = world.blocks["B1"]
    for robot in ("Emil", "Rasmus"):  # pushing its back face; watching from the side
        seen = block(sensors.scan(world, robot, "laser"), "B1", (1.0, 0.4))
        assert seen.centre is not None, seen.why
        tx, ty = _truth(world, robot, b1.pose[0], b1.pose[1])
        assert math.hypot(seen.centre[0] - tx, seen.centre[1] - ty) < 0.02, robot
        assert seen.normal is not None
        turned = square(seen.normal + world.bodies[robot].pose[2] - b1.pose[2])
        assert abs(turned) < math.radians(1.5), robot


def test_the_free_end_of_w1_is_seen_then_hidden_by_the_block() -> None:
    world = _build_wall()
    corner = (3.0, 5.1)  # W1's face towards the robots, at its free end
    scan = sensors.scan(world, "Emil", "laser")
    found = free_end(scan, "W1", 0.4, "left")
    assert isinstance(found, tuple)
    tx, ty = _truth(world, "Emil", *corner)
    assert math.hypot(found[0] - tx, found[1] - ty) < 0.03
    # steered 15 degrees to the right, B1 comes between Emil's laser and that corner
    b1 = world.blocks["B1"]
    b1.pose = (b1.pose[0], b1.pose[1], b1.pose[2] - math.radians(15))
    attach(b1, world.bodies)
    hidden = free_end(sensors.scan(world, "Emil", "laser"), "W1", 0.4, "left")
    assert hidden == "the free end of W1 is hidden behind B1"
    # Rasmus, on the other side, still sees it
    seen = free_end(sensors.scan(world, "Rasmus", "laser"), "W1", 0.4, "left")
    assert isinstance(seen, tuple)
    tx, ty = _truth(world, "Rasmus", *corner)
    assert math.hypot(seen[0] - tx, seen[1] - ty) < 0.03


def test_sonar_localization_pulls_a_wrong_guess_back_to_the_truth() -> None:
    world = World(open_scenario("carry-bar").scenario, 1)
    truth = world.bodies["Emil"].pose
    scan = sensors.scan(world, "Emil", "sonar")
    guess = (truth[0] + 0.15, truth[1] - 0.1, truth[2] + math.radians(4))
    x, y, h = localize(guess, scan, world.segments)
    assert math.hypot(x - truth[0], y - truth[1]) < 0.03
    assert abs(wrap(h - truth[2])) < math.radians(1.5)
    assert localize(guess, {**scan, "hits": [None] * len(scan["hits"])}, world.segments) == guess


def test_square_keeps_a_symmetric_objects_normal_within_a_quarter_turn() -> None:
    assert square(math.radians(100)) == pytest.approx(math.radians(-80))
    assert square(math.radians(-100)) == pytest.approx(math.radians(80))
    assert square(0.3) == pytest.approx(0.3)
