"""A cfgplan robot as a real ROS 2 node through rclpy, with real nodes in other processes (ros2).

Pippi drives on a laser (``/scan``) or, when it fails, a sonar (``/sonar``)
(tests/ros2/data/fallback.lisp, fallback-map.toml: both best effort, as
sensor drivers publish); her ``drive`` publishes ``/cmd_vel``. Real rclpy
nodes (tests/ros2/data/ros_node.py) run in processes of their own, on Fast
DDS (Jazzy's default middleware), in a ROS domain of this test's own with
localhost discovery: one publishes LaserScans on ``/scan`` (2 m: clear),
one on ``/sonar`` (0.5 m: an obstacle), one observes ``/cmd_vel``, the
events and the configuration. ``cfgplan run --robot Pippi --ros2-map ...
--ros2 --ros2-via rclpy`` is the robot. What must happen:

* the robot's Twist reaches the observer with what ``avoid`` computed from
  the laser's scans (0.5 m/s, 0.1 rad/s), so the functionality read ``/scan``;
* the robot is the node ``/Pippi/cfgplan`` in the graph, its status (the
  laser's calls ran) on ``/cfgplan/status``, and its configuration on the
  latched ``/cfgplan/configuration``;
* the fault: the laser's node is killed (SIGKILL). The observer sees the
  laser's failure and the switch to the sonar's configuration on
  ``/cfgplan/events``, the switch within a second of the robot making it (its
  trace), and the Twist becomes the sonar's (0 m/s: the obstacle);
* the fault clears: the laser node started again, its recovery is on the events;
* SIGTERM (what ``ros2 launch`` sends) ends the robot with exit 0, and its node
  leaves the graph.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from tests.backends.support import ROOT
from tests.ros2 import realros
from tests.runtime.netutil import endpoint, free_port, hermetic_config, read_trace

pytestmark = pytest.mark.ros2

DATA = ROOT / "tests" / "ros2" / "data"
NODE = DATA / "ros_node.py"
LIMIT = 60.0  # seconds: DDS discovery (about 2.5 s a pair), interpreters, a loaded machine


class Started:
    """Processes of one test, each stopped by its pid at the end."""

    def __init__(self, folder: Path, env: dict[str, str]) -> None:
        self.folder, self.env = folder, env
        self.processes: list[subprocess.Popen[str]] = []

    def start(self, name: str, args: list[str]) -> subprocess.Popen[str]:
        log = open(self.folder / f"{name}.log", "w", encoding="utf-8")  # noqa: SIM115
        process = subprocess.Popen(
            [sys.executable, *args], cwd=ROOT, env=self.env, stdout=log,
            stderr=subprocess.STDOUT, text=True,
        )  # fmt: skip
        log.close()
        self.processes.append(process)
        return process

    def log(self, name: str) -> str:
        path = self.folder / f"{name}.log"
        return path.read_text("utf-8", errors="replace") if path.exists() else ""

    def stop(self) -> None:
        for process in self.processes:
            if process.poll() is None:
                process.send_signal(signal.SIGINT)
        for process in self.processes:
            try:
                process.wait(timeout=15)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait(timeout=15)


def _until(what: str, found: Callable[[], Any], started: Started, limit: float = LIMIT) -> Any:
    deadline = time.monotonic() + limit
    while time.monotonic() < deadline:
        got = found()
        if got:
            return got
        time.sleep(0.1)
    logs = "\n".join(f"--- {n}\n{started.log(n)[-3000:]}" for n in ("robot", "observer"))
    raise AssertionError(f"not within {limit} s: {what}\n{logs}")


def _seen(path: Path) -> list[dict[str, Any]]:
    if not path.exists():
        return []
    return [json.loads(line) for line in path.read_text("utf-8").split("\n")[:-1]]


def test_a_robot_is_a_ros_2_node_on_dds_and_switches_when_its_laser_dies(tmp_path: Path) -> None:
    realros.rclpy()
    domain = realros.domain()
    started = Started(tmp_path, realros.ros_env(domain))
    seen, trace = tmp_path / "observed.jsonl", tmp_path / "trace.jsonl"
    node_args = [str(NODE), "observe", str(seen), "/cfgplan/events", "/cfgplan/configuration"]
    node_args.append("/cfgplan/status")
    robot_args = [
        "-m", "cfgplan", "run", str(DATA / "fallback.lisp"), str(DATA / "fallback-state.lisp"),
        "--impl", str(DATA / "drive_impl.py"), "--robot", "Pippi",
        "--ros2-map", str(DATA / "fallback-map.toml"), "--ros2", "--ros2-via", "rclpy",
        "--rate", "10", "--duration", "300", "--trace", str(trace),
        "--zenoh-config", str(hermetic_config(tmp_path)), "--listen", endpoint(free_port()),
    ]  # fmt: skip
    try:
        started.start("observer", node_args)
        laser = started.start("laser", [str(NODE), "scan", "/scan", "2.0"])
        started.start("sonar", [str(NODE), "scan", "/sonar", "0.5"])
        robot = started.start("robot", robot_args)

        def twists(x: float) -> list[dict[str, Any]]:
            return [r for r in _seen(seen) if r["topic"] == "/cmd_vel" and r["x"] == x]

        clear = _until("the laser's Twist at the observer", lambda: twists(0.5), started)
        time.sleep(1.0)  # the laser's configuration running for a while
        assert clear[0]["z"] == pytest.approx(0.1)
        _until(
            "/Pippi/cfgplan in the observer's graph",
            lambda: any("/Pippi/cfgplan" in r.get("nodes", []) for r in _seen(seen)),
            started,
        )
        status = [r["data"] for r in _seen(seen) if r["topic"] == "/cfgplan/status"]
        assert (
            status
            and {"functionality": "laser(Pippi)", "status": "ran"}.items()
            <= next(
                c for c in status[-1]["calls"].values() if c["functionality"] == "laser(Pippi)"
            ).items()
        ), status[-1:]
        configured = [r["data"] for r in _seen(seen) if r["topic"] == "/cfgplan/configuration"]
        assert configured and "laser(Pippi)" in " ".join(configured[-1]["functionalities"])

        killed = time.monotonic()
        os.kill(laser.pid, signal.SIGKILL)  # the fault: the laser's driver dies

        def events(kind: str, since: float) -> list[dict[str, Any]]:
            return [
                r for r in _seen(seen)
                if r["topic"] == "/cfgplan/events" and r["data"]["event"] == kind
                and r["at"] > since
            ]  # fmt: skip

        switch = _until("the switch on /cfgplan/events", lambda: events("switch", killed), started)[
            0
        ]
        failure = events("failure", killed)
        assert failure and failure[0]["data"]["resource"] == "laser(Pippi)", failure
        assert switch["data"]["cause"].startswith("laser(Pippi)"), switch
        made = _until(
            "the switch in the robot's trace",
            lambda: [
                r for r in read_trace(trace)
                if r["event"] == "switch" and r["id"] == switch["data"]["id"]
            ],
            started,
        )[0]  # fmt: skip
        assert made["id"] == switch["data"]["id"] and made["t"] == switch["data"]["t"]
        # within a second of the robot making it (both wall clocks: this machine's)
        assert 0.0 <= switch["wall"] - made["t"] < 1.0, (switch, made)
        _until("the sonar's Twist (the obstacle: 0 m/s)", lambda: twists(0.0), started)
        configured = [
            r["data"]
            for r in _seen(seen)
            if r["topic"] == "/cfgplan/configuration" and r["at"] > killed
        ]
        assert configured and "sonar(Pippi)" in " ".join(configured[-1]["functionalities"])

        cleared = time.monotonic()
        laser = started.start("laser", [str(NODE), "scan", "/scan", "2.0"])  # the fault clears
        _until(
            "the laser's recovery on /cfgplan/events",
            lambda: [
                r for r in events("recovery", cleared) if r["data"]["resource"] == "laser(Pippi)"
            ],
            started,
        )

        robot.send_signal(signal.SIGTERM)  # as ros2 launch stops a node
        assert robot.wait(timeout=30) == 0, started.log("robot")
        gone_after = time.monotonic()
        _until(
            "/Pippi/cfgplan gone from the observer's graph",
            lambda: any(
                r["at"] > gone_after and "/Pippi/cfgplan" not in r["nodes"]
                for r in _seen(seen)
                if r["topic"] == "graph"
            ),
            started,
        )
    finally:
        started.stop()


def test_the_node_is_the_robots_with_use_sim_time_and_closes(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """``/<robot>/cfgplan`` in the domain given; ``use_sim_time`` is the node's
    parameter, and with it (and no ``/clock`` yet) the stamps are sim time's 0,
    without it the wall clock's; close() shuts the node's own context down,
    twice is once."""
    realros.rclpy()
    import time as wall

    from cfgplan.ros2.node import NodeOptions, RosNode

    monkeypatch.setenv("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    simulated = RosNode("Pippi", NodeOptions(domain_id=realros.domain(), use_sim_time=True))
    real = RosNode("Emil", NodeOptions(domain_id=realros.domain()))
    try:
        assert simulated.name == "/Pippi/cfgplan" and real.name == "/Emil/cfgplan"
        assert simulated.node.get_parameter("use_sim_time").value is True
        assert real.node.get_parameter("use_sim_time").value is False
        assert simulated.now_ns() == 0
        assert abs(real.now_ns() - wall.time_ns()) < 5 * 10**9
    finally:
        simulated.close()
        real.close()
    assert not simulated.context.ok() and not real.context.ok()
    simulated.close()  # once is enough
