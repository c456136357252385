"""Functionalities bound to ROS 2 topics, against a plain zenoh-python "ROS 2 node".

The test's ROS side is written from rmw_zenoh's design document alone: the key
expressions, the attachment and the token prefix are spelled out literally
here, the CDR made and read by rosbags itself (not by :mod:`cfgplan.ros2`).
It checks that a rmw_zenoh-formatted ``sensor_msgs/msg/LaserScan`` reaches
the functionality bound to ``/scan``, that an action's bound input comes out
on ``/cmd_vel`` as a ``geometry_msgs/msg/Twist`` rosbags decodes, and that a
silent topic is a failure the monitor sees (the slow test, through ``cfgplan
run``). Hermetic: loopback, free ports, scouting off, bounded waits.
"""

from __future__ import annotations

import json
import os
import re
import signal
import struct
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy
import pytest

from cfgplan.problem import load
from cfgplan.ros2 import codec
from cfgplan.ros2.bindings import Latest, TopicBindings
from cfgplan.ros2.topics import load_map
from cfgplan.runtime.faults import ResourceFailure
from cfgplan.runtime.registry import Registry
from tests.backends.support import ROOT
from tests.runtime.netutil import (
    endpoint,
    first,
    free_port,
    hermetic_config,
    processes,
    read_trace,
    wait_for,
)

zenoh = pytest.importorskip("zenoh")
typesys = pytest.importorskip("rosbags.typesys")

DATA = Path(__file__).parent / "data"
DRIVE = [str(DATA / "drive.lisp"), str(DATA / "drive-state.lisp")]
STORE = typesys.get_typestore(typesys.Stores.ROS2_JAZZY)
SCAN_KEY = "0/scan/sensor_msgs::msg::dds_::LaserScan_/" + STORE.hash_rihs01(
    "sensor_msgs/msg/LaserScan"
)
CMD_KEY = "0/cmd_vel/geometry_msgs::msg::dds_::Twist_/" + STORE.hash_rihs01(
    "geometry_msgs/msg/Twist"
)
"""design.md: <domain_id>/<fully qualified name>/<type name>/<type hash>."""
LIMIT = 60.0


def _scan(ranges: list[float]) -> bytes:
    """A LaserScan as a ROS 2 driver would send it: CDR by rosbags."""
    types = STORE.types
    header = types["std_msgs/msg/Header"](
        stamp=types["builtin_interfaces/msg/Time"](sec=1, nanosec=2), frame_id="laser"
    )
    message = types["sensor_msgs/msg/LaserScan"](
        header=header, angle_min=-1.0, angle_max=1.0, angle_increment=1.0, time_increment=0.0,
        scan_time=0.1, range_min=0.1, range_max=10.0,
        ranges=numpy.array(ranges, dtype=numpy.float32),
        intensities=numpy.array([], dtype=numpy.float32),
    )  # fmt: skip
    return bytes(STORE.serialize_cdr(message, "sensor_msgs/msg/LaserScan"))


def _attachment(number: int) -> bytes:
    """design.md, "Publishers": sequence number, source timestamp (int64 LE), GID (16)."""
    return struct.pack("<qqB", number, time.time_ns(), 16) + bytes(range(16))


class RosSide:
    """A laser driver and a base, as rmw_zenoh nodes would be, from plain zenoh-python."""

    def __init__(self, config: Path, port: int) -> None:
        conf = zenoh.Config.from_file(str(config))
        conf.insert_json5("mode", '"peer"')
        conf.insert_json5("listen/endpoints", json.dumps([endpoint(port)]))
        self.session = zenoh.open(conf)
        self.lock = threading.Lock()
        self.commands: list[tuple[bytes, bytes | None]] = []
        self.tokens: set[str] = set()
        self.scans = self.session.declare_publisher(SCAN_KEY)
        self.number = 0
        self.base = self.session.declare_subscriber(CMD_KEY, self.on_command)
        self.watcher = self.session.liveliness().declare_subscriber(
            "@ros2_lv/0/**", self.on_token, history=True
        )

    def publish_scan(self, ranges: list[float]) -> None:
        self.number += 1
        self.scans.put(_scan(ranges), attachment=_attachment(self.number))

    def on_command(self, sample: Any) -> None:
        extra = None if sample.attachment is None else sample.attachment.to_bytes()
        with self.lock:
            self.commands.append((sample.payload.to_bytes(), extra))

    def on_token(self, sample: Any) -> None:
        if sample.kind == zenoh.SampleKind.PUT:
            with self.lock:
                self.tokens.add(str(sample.key_expr))

    def twists(self) -> list[Any]:
        with self.lock:
            got = list(self.commands)
        return [STORE.deserialize_cdr(payload, "geometry_msgs/msg/Twist") for payload, _ in got]

    def close(self) -> None:
        self.session.close()


@pytest.fixture
def ros(tmp_path: Path) -> Iterator[tuple[RosSide, Path, int]]:
    config, port = hermetic_config(tmp_path), free_port()
    side = RosSide(config, port)
    try:
        yield side, config, port
    finally:
        side.close()


def _robot_session(config: Path, port: int) -> Any:
    conf = zenoh.Config.from_file(str(config))
    conf.insert_json5("mode", '"peer"')
    conf.insert_json5("listen/endpoints", "[]")
    conf.insert_json5("connect/endpoints", json.dumps([endpoint(port)]))
    return zenoh.open(conf)


def test_a_scan_reaches_the_laser_and_the_drive_publishes_a_twist(
    ros: tuple[RosSide, Path, int],
) -> None:
    """In one process: the robot's bindings on a session of their own, the ROS side on another."""
    side, config, port = ros
    problem = load(*DRIVE)
    topics = load_map(DATA / "drive-map.toml", problem.domain, problem.task.agents)
    session = _robot_session(config, port)
    try:
        bound = TopicBindings(session, "Pippi", topics)
        registry = bound.registry(Registry())
        assert registry.names() == ["drive", "laser"]  # the map implements both
        node = "@ros2_lv/0/" + str(session.zid())
        wait_for(
            "the node's, subscriber's and publisher's tokens",
            lambda: (
                {"ok": True}
                if {t.split("/")[5] for t in side.tokens if t.startswith(node)}
                == {"NN", "MS", "MP"}
                else None
            ),
            LIMIT,
        )
        (scan_token,) = [t for t in side.tokens if t.startswith(node) and "/MS/" in t]
        hash_ = SCAN_KEY.split("/")[-1]
        assert scan_token == (
            f"{node}/1/1/MS/%/%/cfgplan_Pippi_topics/%scan/sensor_msgs::msg::dds_::LaserScan_/"
            f"{hash_}/::,10:,:,:,,"
        )
        laser = registry.lookup("laser")

        def scanned() -> dict[str, object] | None:
            side.publish_scan([2.0, 3.5])
            got = laser()
            return got if isinstance(got, dict) else None

        value = wait_for("a scan at the laser", scanned, LIMIT, poll=0.1)
        assert value["ranges"] == [2.0, 3.5] and value["header"]["frame_id"] == "laser"  # type: ignore[index]
        registry.lookup("drive")({"linear": {"x": 0.5}, "angular": {"z": 0.1}})
        twist = wait_for(
            "a twist on /cmd_vel",
            lambda: {"t": side.twists()[0]} if side.twists() else None,
            LIMIT,
        )["t"]
        assert (twist.linear.x, twist.angular.z) == (0.5, 0.1)  # type: ignore[attr-defined]
        extra = side.commands[0][1]
        assert extra is not None and len(extra) == 33 and struct.unpack_from("<q", extra)[0] == 1
        bound.close()
    finally:
        session.close()


def test_a_silent_topic_is_a_failing_sensor() -> None:
    """No message yet: no data for the timeout, then ResourceFailure; a message: its value."""
    problem = load(*DRIVE)
    (laser, _) = load_map(DATA / "drive-map.toml", problem.domain, problem.task.agents).bindings
    latest = Latest(since=100.0)
    assert latest.read(laser, now=100.4) is None
    with pytest.raises(ResourceFailure, match=r"topic /scan .*no message yet for 0.6 s"):
        latest.read(laser, now=100.6)
    scan = codec.cdr_of_value(laser.msg_type, {"ranges": [1.5]})
    latest.raw, latest.at = scan, 101.0  # kept as it came, decoded when read
    assert latest.read(laser, now=101.2)["ranges"] == [1.5]
    latest.raw = b"\x00\x01\x00\x00 not a scan"  # the newest undecodable: the last good one
    assert latest.read(laser, now=101.3)["ranges"] == [1.5] and latest.undecodable == 1
    with pytest.raises(ResourceFailure, match=r"no message for 0.7 s \(timeout 0.5 s\)"):
        latest.read(laser, now=101.7)


@pytest.mark.slow
def test_cfgplan_run_drives_on_ros_scans_and_fails_when_they_stop(
    ros: tuple[RosSide, Path, int], tmp_path: Path
) -> None:
    """``cfgplan run --robot Pippi --ros2-map``: scans from the ROS side make avoid
    send 0.5 m/s on /cmd_vel (an obstacle at 0.5 m: 0); when the scans stop, the
    monitor reports the laser failed (the topic silent) and the run stops safely."""
    side, config, port = ros
    trace = tmp_path / "pippi.jsonl"
    args = ["-m", "cfgplan", "run", *DRIVE, "--impl", str(DATA / "drive_impl.py")]
    args += ["--robot", "Pippi", "--ros2-map", str(DATA / "drive-map.toml"), "--rate", "20"]
    args += ["--zenoh-config", str(config), "--connect", endpoint(port), "--trace", str(trace)]
    args += ["--duration", "30"]
    with processes() as running:
        robot = running.start(args, tmp_path / "pippi.log")
        deadline = time.monotonic() + LIMIT
        while not any(t.linear.x == 0.5 for t in side.twists()):
            assert time.monotonic() < deadline, "no 0.5 m/s on /cmd_vel"
            side.publish_scan([2.0, 3.0])
            time.sleep(0.05)
        for _ in range(20):
            side.publish_scan([0.5, 3.0])
            time.sleep(0.05)
        assert any(t.linear.x == 0.0 for t in side.twists())
        failure = wait_for(
            "the laser's failure",
            first(trace, lambda r: r["event"] == "failure"),
            LIMIT,
        )
        assert robot.wait(LIMIT) == 3  # nothing admissible without the laser
    assert failure["resource"] == "laser(Pippi)" and failure["how"] == "reported"
    assert "topic /scan (sensor_msgs/msg/LaserScan): no message for" in str(failure["detail"])
    assert any(r["event"] == "no-configuration" for r in read_trace(trace))
    assert "Traceback" not in (tmp_path / "pippi.log").read_text()


@pytest.mark.slow
def test_cfgplan_launch_with_a_map_reaches_a_ros_node_it_connects_to(
    ros: tuple[RosSide, Path, int],
) -> None:
    """``cfgplan launch ... --ros2-map FILE --connect ENDPOINT``: the launched robot
    meets the ROS side through the endpoint, drives on its scans; SIGTERM to the
    launch stops it (exit 0) and its pid is gone."""
    side, _, port = ros
    args = [sys.executable, "-m", "cfgplan", "launch", *DRIVE]
    args += ["--impl", str(DATA / "drive_impl.py"), "--ros2-map", str(DATA / "drive-map.toml")]
    args += ["--connect", endpoint(port), "--rate", "20"]
    launched = subprocess.Popen(
        args, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    try:
        deadline = time.monotonic() + LIMIT
        while not any(t.linear.x == 0.5 for t in side.twists()):
            assert time.monotonic() < deadline, "no 0.5 m/s on /cmd_vel"
            assert launched.poll() is None, launched.communicate()
            side.publish_scan([2.0, 3.0])
            time.sleep(0.05)
        launched.send_signal(signal.SIGTERM)
        out, err = launched.communicate(timeout=LIMIT)
    finally:
        if launched.poll() is None:
            launched.kill()
            launched.communicate(timeout=30)
    assert launched.returncode == 0, f"{out}\n{err}"
    (pid,) = [int(p) for p in re.findall(r"^Pippi \| \(started: pid (\d+)\)", out, re.M)]
    with pytest.raises(ProcessLookupError):
        os.kill(pid, 0)
