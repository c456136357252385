"""The ROS 2 topic map (``--ros2-map FILE``): read, and checked against the domain."""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from cfgplan.problem import load
from cfgplan.ros2.codec import cdr_of_value, value_of_cdr
from cfgplan.ros2.topics import Binding, load_map, parse_map
from cfgplan.runtime.errors import RunError
from tests.backends.support import ROOT

pytest.importorskip("rosbags")

DATA = Path(__file__).parent / "data"
DRIVE = load(DATA / "drive.lisp", DATA / "drive-state.lisp")


def _parse(text: str) -> list[Binding]:
    found = parse_map(textwrap.dedent(text), "map.toml", DRIVE.domain, DRIVE.task.agents)
    return list(found.bindings)


def _error(text: str) -> RunError:
    with pytest.raises(RunError) as caught:
        _parse(text)
    return caught.value


def test_the_example_map_binds_the_laser_and_the_drive() -> None:
    """Each [[bind]] names its functionality, port (with its position), topic, type and line."""
    found = load_map(DATA / "drive-map.toml", DRIVE.domain, DRIVE.task.agents)
    laser, drive = found.bindings
    assert (laser.functionality, laser.direction, laser.port, laser.index) == (
        "laser",
        "output",
        "scan",
        0,
    )
    assert (laser.topic, laser.msg_type, laser.timeout, laser.line) == (
        "/scan",
        "sensor_msgs/msg/LaserScan",
        0.5,
        2,
    )
    assert (drive.direction, drive.port, drive.objects, drive.inputs, drive.outputs) == (
        "input",
        "cmd",
        0,
        1,
        0,
    )
    assert found.implements("laser", "Pippi") and found.implements("drive", "Pippi")
    assert not found.implements("avoid", "Pippi")


@pytest.mark.parametrize(
    ("text", "message", "line"),
    [
        (
            """
            [[bind]]
            functionality = "lidar"
            output = "scan"
            topic = "/scan"
            type = "sensor_msgs/msg/LaserScan"
            """,
            "no functionality lidar in the domain (its: avoid, drive, laser)",
            3,
        ),
        (
            """
            [[bind]]
            functionality = "laser"
            output = "image"
            topic = "/scan"
            type = "sensor_msgs/msg/LaserScan"
            """,
            "laser has no output 'image' (its outputs: scan)",
            4,
        ),
        (
            """
            [[bind]]
            functionality = "laser"
            output = "scan"
            topic = "/scan"
            type = "sensor_msgs/msg/LaserScann"
            """,
            "unknown ROS 2 message type sensor_msgs/msg/LaserScann",
            6,
        ),
        (
            """
            [[bind]]
            functionality = "laser"
            output = "scan"
            topic = "scan"
            type = "sensor_msgs/msg/LaserScan"
            """,
            "'scan' is not an absolute ROS 2 topic name",
            5,
        ),
        (
            """
            [[bind]]
            functionality = "laser"
            output = "scan"
            topic = "/scan"
            type = "sensor_msgs/msg/LaserScan"
            robot = "Emil"
            """,
            "no robot Emil in the state (its: Pippi)",
            7,
        ),
        (
            """
            [[bind]]
            functionality = "laser"
            output = "scan"
            topic = "/scan"
            type = "sensor_msgs/msg/LaserScan"
            rate = 10
            """,
            "[[bind]] has no key rate",
            7,
        ),
        (
            """
            [[bind]]
            functionality = "avoid"
            input = "scan"
            topic = "/scan"
            type = "sensor_msgs/msg/LaserScan"
            """,
            "avoid has outputs: only an action's inputs",
            4,
        ),
        (
            """
            [[bind]]
            functionality = "laser"
            output = "scan"
            topic = "/scan"
            type = "sensor_msgs/msg/LaserScan"

            [[bind]]
            functionality = "laser"
            output = "scan"
            topic = "/scan2"
            type = "sensor_msgs/msg/LaserScan"
            """,
            "laser output scan is bound twice (first at line 2)",
            8,
        ),
        (
            """
            [[bind]]
            functionality = "laser"
            topic = "/scan"
            type = "sensor_msgs/msg/LaserScan"
            """,
            'binds one port: give input = "..." or output = "..."',
            2,
        ),
        ("bind = [1]", "[[bind]] entry 1 is 1, not a table of keys", 1),
        (
            """
            [[bind]]
            functionality = "laser"
            output = "scan"
            topic = "/scan"
            type = "sensor_msgs/msg/LaserScan"
            timeout = nan
            """,
            "timeout nan is not a number of seconds above 0",
            7,
        ),
        (
            """
            [[bind]]
            functionality = "laser"
            output = "scan"
            topic = "/scan"
            type = "sensor_msgs/msg/LaserScan"
            reliability = "best-effort"
            """,
            "reliability 'best-effort' is not one of: reliable, best_effort",
            7,
        ),
        (
            """
            [[bind]]
            functionality = "laser"
            output = "scan"
            topic = "/scan"
            depth = 0
            type = "sensor_msgs/msg/LaserScan"
            """,
            "depth 0 is not a whole number of messages, 1 to 10000",
            6,
        ),
    ],
)
def test_a_wrong_binding_is_said_with_its_file_and_line(text: str, message: str, line: int) -> None:
    """Every mistake names the map file and the line of the key at fault (or of its [[bind]])."""
    error = _error(text)
    assert message in error.message
    assert (error.file, error.line) == ("map.toml", line)


def test_a_map_that_is_not_toml_says_where() -> None:
    error = _error('[[bind]]\nfunctionality = "laser\n')
    assert error.message.startswith("the ROS 2 map is not TOML") and error.line == 2


def test_the_cli_refuses_a_wrong_map_before_the_network(tmp_path: Path) -> None:
    """cfgplan run: exit 1, compiler-style file:line, no traceback, no session opened."""
    bad = tmp_path / "map.toml"
    bad.write_text('[[bind]]\nfunctionality = "laser"\noutput = "scans"\ntopic = "/scan"\n'
                   'type = "sensor_msgs/msg/LaserScan"\n')  # fmt: skip
    done = subprocess.run(
        [sys.executable, "-m", "cfgplan", "run",
         str(DATA / "drive.lisp"), str(DATA / "drive-state.lisp"),
        "--impl", str(DATA / "drive_impl.py"), "--robot", "Pippi", "--ros2-map", str(bad)],
        capture_output=True, text=True, timeout=120, cwd=ROOT,
    )  # fmt: skip
    assert done.returncode == 1
    assert f"{bad}:3:1: error: laser has no output 'scans' (its outputs: scan)" in done.stderr
    assert "Traceback" not in done.stderr and "without keys" not in done.stderr


def test_values_and_cdr_round_trip_and_wrong_fields_are_named() -> None:
    """A dict becomes CDR (header 00 01 00 00) and comes back; a field left out is zero."""
    payload = cdr_of_value("geometry_msgs/msg/Twist", {"linear": {"x": 0.5}})
    assert payload[:4] == b"\x00\x01\x00\x00"
    assert value_of_cdr("geometry_msgs/msg/Twist", payload) == {
        "linear": {"x": 0.5, "y": 0.0, "z": 0.0},
        "angular": {"x": 0.0, "y": 0.0, "z": 0.0},
    }
    with pytest.raises(ValueError, match=r"Twist.linear.x: 'fast' is not a number"):
        cdr_of_value("geometry_msgs/msg/Twist", {"linear": {"x": "fast"}})
    with pytest.raises(ValueError, match="has no field speed"):
        cdr_of_value("geometry_msgs/msg/Twist", {"speed": 1})


def test_a_bindings_qos_is_the_maps_in_rmws_numbers() -> None:
    """reliability, durability and depth of a [[bind]] are its QoS (rmw's
    enumerations, as a token and rclpy's profile take them); left out, rclcpp's
    default: reliable, volatile, keep last 10 (the rmw_zenoh token's as before)."""
    from cfgplan.ros2 import rmw_zenoh as wire

    laser, drive = _parse(
        """
        [[bind]]
        functionality = "laser"
        output = "scan"
        topic = "/scan"
        type = "sensor_msgs/msg/LaserScan"
        reliability = "best_effort"
        durability = "transient_local"
        depth = 5

        [[bind]]
        functionality = "drive"
        input = "cmd"
        topic = "/cmd_vel"
        type = "geometry_msgs/msg/Twist"
        """
    )
    assert laser.qos == wire.QoS(reliability=2, durability=1, history=1, depth=5)
    assert drive.qos == wire.PUBLISHER_QOS
    assert wire.qos_key_expr(laser.qos) == "2:1:,5:,:,:,,"


def test_the_way_of_speaking_ros_2_is_chosen_as_documented(monkeypatch: pytest.MonkeyPatch) -> None:
    """--ros2-via, else CFGPLAN_ROS2_VIA, else rclpy where it imports, else
    zenoh; rclpy asked for where it is missing says how to get it."""
    import importlib.util

    from cfgplan.ros2.node import choose_via

    assert choose_via("zenoh", {"CFGPLAN_ROS2_VIA": "rclpy"}) == "zenoh"
    assert choose_via(None, {"CFGPLAN_ROS2_VIA": "zenoh"}) == "zenoh"
    with pytest.raises(RunError, match="give one of rclpy, zenoh"):
        choose_via(None, {"CFGPLAN_ROS2_VIA": "dds"})
    real = importlib.util.find_spec
    monkeypatch.setattr(
        importlib.util, "find_spec", lambda name, *a: None if name == "rclpy" else real(name, *a)
    )
    assert choose_via(None, {}) == "zenoh"
    with pytest.raises(RunError, match="rclpy cannot be imported") as caught:
        choose_via("rclpy", {})
    assert "ros2-rclpy" in (caught.value.hint or "")
    monkeypatch.setattr(importlib.util, "find_spec", lambda name, *a: object())
    assert choose_via(None, {}) == "rclpy"


@pytest.mark.parametrize(
    ("flags", "message"),
    [
        (["--ros2-via", "rclpy"], "--ros2-via"),
        (["--use-sim-time"], "--use-sim-time"),
        (["--ros2", "--ros2-via", "dds"], "'dds': give rclpy or zenoh"),
    ],
)
def test_the_ways_options_are_usage_errors_where_they_mean_nothing(
    flags: list[str], message: str
) -> None:
    """--ros2-via and --use-sim-time without --ros2 or --ros2-map, or a way
    that is not rclpy or zenoh: exit 2, said, before anything runs."""
    done = subprocess.run(
        [sys.executable, "-m", "cfgplan", "run",
         str(DATA / "drive.lisp"), str(DATA / "drive-state.lisp"),
         "--impl", str(DATA / "drive_impl.py"), "--robot", "Pippi", *flags],
        capture_output=True, text=True, timeout=120, cwd=ROOT,
    )  # fmt: skip
    assert done.returncode == 2, done.stderr
    assert message in done.stderr and "Traceback" not in done.stderr
