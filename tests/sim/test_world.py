"""The world's physics and sensors (6.1, 6.2.1, 6.3.1, 6.4): each behaves as
its docstring says, with numbers."""

from __future__ import annotations

import math

import pytest

from cfgplan.runtime import ResourceFailure
from cfgplan.sim import sensors
from cfgplan.sim.blocks import alignment
from cfgplan.sim.run import open_scenario
from cfgplan.sim.scenario import Scenario
from cfgplan.sim.world import World, map_segments


def _world(name: str, seed: int = 1, **changes: object) -> World:
    scenario = open_scenario(name).scenario
    if changes:
        scenario = scenario.model_copy(update=changes)
    return World(scenario, seed)


def _run(world: World, seconds: float, drive: dict[str, tuple[float, float]] | None = None) -> None:
    """Step the world, renewing the motor commands every step."""
    for _ in range(round(seconds / 0.1)):
        for name, (v, w) in (drive or {}).items():
            world.bodies[name].drive(world.time, v, w)
        world.step(0.1)


def test_the_map_is_the_rooms_with_the_door_cut_out() -> None:
    scenario: Scenario = open_scenario("cross-door").scenario
    walls = map_segments(scenario)
    # Room1 and Room2 share y = 3: once, less the door's metre in the middle
    shared = sorted(w for w in walls if w[1] == w[3] == 3.0)
    assert shared == [(0.0, 3.0, 1.0, 3.0), (2.0, 3.0, 3.0, 3.0)]
    assert len(walls) == 8  # 4 + 4 sides, the shared one in two pieces, once


def test_motors_stop_when_commands_stop_and_odometry_drifts() -> None:
    world = _world("cross-door")
    body = world.bodies["Pippi"]
    start = body.pose
    body.drive(world.time, 0.3, 0.0)
    _run(world, 2.0)  # nobody renews the command: the watchdog (0.3 s) stops her
    moved = math.hypot(body.pose[0] - start[0], body.pose[1] - start[1])
    assert 0.08 < moved < 0.1
    # dead reckoning follows what the wheels did, with a little error
    world = _world("cross-door")
    body = world.bodies["Emil"]
    _run(world, 6.0, {"Emil": (0.3, 0.0)})
    true, odo = body.pose, body.odometry
    travelled = body.travelled
    assert 1.6 < travelled < 2.0
    error = math.hypot(true[0] - odo[0], true[1] - odo[1])
    assert 0.0 < error < 0.08
    assert abs(true[2] - odo[2]) == pytest.approx(math.radians(1.0) * travelled, abs=0.01)


def test_a_robot_driving_into_a_wall_stops_against_it_and_counts_a_bump() -> None:
    world = _world("cross-door")
    body = world.bodies["Emil"]  # at (0.35, 0.35): drive west into the wall x = 0
    _run(world, 1.0, {"Emil": (0.0, 2.0)})
    heading = body.pose[2]
    _run(world, 4.0, {"Emil": (0.3, 0.0)})
    assert body.bumps == 1
    x, y, _ = body.pose
    nearest = min(x, y)  # the walls x = 0 and y = 0
    assert 0.2 <= nearest < 0.21  # stopped at the step before touching
    assert heading == pytest.approx(body.pose[2], abs=0.2)


def test_the_camera_measures_only_beyond_2_m_and_not_through_walls() -> None:
    world = _world("cross-door")
    image = sensors.camera(world, "Emil")
    pippi = image["sees"]["Pippi"]
    door = image["sees"]["Door1"]
    assert pippi[1] is not None and door[1] is not None and door[2] is not None
    assert door[1] == pytest.approx(math.hypot(1.15, 2.65), rel=0.05)
    # Pippi 1.5 m in front of Emil: a bearing, no range
    world.bodies["Pippi"].pose = (0.35 + 1.0, 0.35 + 1.1, 0.0)
    near = sensors.camera(world, "Emil")["sees"]["Pippi"]
    assert near[1] is None and near[2] is None
    assert near[0] == pytest.approx(math.atan2(1.1, 1.0) - math.radians(48), abs=0.05)
    # Pippi in Room2 beside the door: the wall hides her
    world.bodies["Pippi"].pose = (0.5, 4.5, 0.0)
    assert "Pippi" not in sensors.camera(world, "Emil")["sees"]
    # behind Emil's fixed camera (90 degrees): not seen either
    world.bodies["Pippi"].pose = (0.3, 0.3 - 0.25, 0.0)
    assert "Pippi" not in sensors.camera(world, "Emil")["sees"]


def test_the_compass_reads_off_in_a_magnetic_disturbance_only() -> None:
    world = _world("cross-door")
    emil = world.bodies["Emil"]
    emil.pose = (2.5, 0.5, emil.pose[2])  # 1.8 m from the disturbance
    far = [sensors.compass(world, "Emil") - emil.pose[2] for _ in range(50)]
    assert abs(sum(far) / len(far)) < math.radians(0.5)  # noise around the truth
    emil.pose = (0.9, 1.3, emil.pose[2])  # in the disturbance's centre: 70 degrees off
    near = [sensors.compass(world, "Emil") - emil.pose[2] for _ in range(50)]
    assert sum(near) / len(near) == pytest.approx(math.radians(70), abs=math.radians(1))


def test_a_broken_sensor_or_one_not_carried_is_a_resource_failure() -> None:
    world = _world("carry-bar")
    with pytest.raises(ResourceFailure, match="Pippi has no laser"):
        sensors.scan(world, "Pippi", "laser")
    sensors.scan(world, "Emil", "laser")
    world.bodies["Emil"].broken.add("laser")
    with pytest.raises(ResourceFailure, match="does not answer"):
        sensors.scan(world, "Emil", "laser")


def test_the_laser_sees_a_robots_post_and_the_noise_is_seeded() -> None:
    world = _world("carry-bar")
    scan = sensors.scan(world, "Emil", "laser")
    hits = [r for r, h in zip(scan["ranges"], scan["hits"], strict=True) if h == "Pippi"]
    truth = math.hypot(1.0 - 0.4, 1.3 - 0.26) - 0.05  # centre to centre, less the post
    assert len(hits) >= 3 and min(hits) == pytest.approx(truth, abs=0.02)
    again = sensors.scan(_world("carry-bar"), "Emil", "laser")
    other = sensors.scan(_world("carry-bar", seed=2), "Emil", "laser")
    assert again == scan and other["ranges"] != scan["ranges"]


def test_the_bar_falls_when_the_robots_part() -> None:
    world = _world("carry-bar")
    assert world.bar_length() == pytest.approx(1.2, abs=0.01)
    _run(world, 1.0, {"Pippi": (0.3, 0.0)})  # Pippi drives off alone
    assert world.bar_dropped is not None
    t, d = world.bar_dropped
    assert 0.5 < t < 1.0 and d == pytest.approx(1.4, abs=0.03)


def test_a_block_moves_only_when_both_push_and_turns_when_they_push_unequally() -> None:
    world = _world("build-wall")
    b1 = world.blocks["B1"]
    start = b1.pose
    _run(world, 2.0, {"Pippi": (0.1, 0.0)})  # one robot alone: too heavy
    assert b1.pose == start
    _run(world, 2.0, {"Pippi": (0.1, 0.0), "Emil": (0.1, 0.0)})
    x, y, h = b1.pose
    assert math.hypot(x - start[0], y - start[1]) == pytest.approx(0.2, abs=0.02)
    assert h == pytest.approx(start[2], abs=0.02)
    # Emil (right) pushes harder: the block turns left, the pushers stay on its face
    _run(world, 2.0, {"Pippi": (0.05, 0.0), "Emil": (0.1, 0.05 / 0.96)})
    assert b1.pose[2] - h == pytest.approx(0.05 / 0.96 * 2.0, abs=0.02)
    emil = world.bodies["Emil"]
    assert emil.attached is not None and abs(emil.attached.delta) < 0.05
    across, depth, turn = alignment(b1, world.walls["W1"])
    assert abs(turn) > 0.05
    assert depth < -1.5 and across < -0.5  # short of its slot, to its left


def test_a_block_pushed_into_a_wall_jams() -> None:
    world = _world("build-wall")
    b1 = world.blocks["B1"]
    b1.pose = (b1.pose[0], 5.9 - 0.3, math.radians(90))  # its front 10 cm from the room's wall
    from cfgplan.sim.blocks import attach

    attach(b1, world.bodies)
    _run(world, 3.0, {"Pippi": (0.1, 0.0), "Emil": (0.1, 0.0)})
    assert b1.jams == 1
    assert b1.pose[1] + 0.2 <= 6.0
