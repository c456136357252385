"""Against a real ROS 2 installation with rmw_zenoh: skipped where ``ros2`` is absent.

Where the ``ros2`` command and ``rmw_zenoh_cpp`` exist (a sourced ROS 2
Jazzy or later), this starts an ``rmw_zenohd`` router on a free loopback port
(``ZENOH_CONFIG_OVERRIDE``, rmw_zenoh's way to change one key of its Zenoh
configuration), launches the cross-door example (examples/cross-door/ros2-map.toml,
``--ros2``) connected to it, and checks with the ROS 2 tools themselves that
``ros2 topic list`` shows ``/door_estimate``, ``/cfgplan/events`` and the
channel topic, that ``ros2 topic echo`` receives the door estimate as a
``geometry_msgs/msg/PoseStamped`` in Pippi's frame, and the channel
``pos(Pippi, Door1)`` as a ``std_msgs/msg/String``. Every process is
stopped by its pid, every wait bounded. It has not been run where cfgplan is
developed (no ROS 2 there): docs/how-to/ros2.md says so.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.backends.support import DOMAINS, EXAMPLE_IMPL, ROOT
from tests.runtime.netutil import endpoint, free_port

ROS2 = shutil.which("ros2")
pytestmark = pytest.mark.skipif(
    ROS2 is None,
    reason="no `ros2` command here: source a ROS 2 (Jazzy or later) with rmw_zenoh_cpp "
    "to check cfgplan against real ROS 2 tools; the offline tests check the documented layout",
)
LIMIT = 60.0
MAP = ROOT / "examples" / "cross-door" / "ros2-map.toml"
STEP1 = [
    str(DOMAINS / "cross-door/domain.lisp"),
    str(DOMAINS / "cross-door/state-6.2.2-step1.lisp"),
]


@contextlib.contextmanager
def _started(args: list[str], env: dict[str, str], log: Path) -> Iterator[subprocess.Popen[str]]:
    out = open(log, "w", encoding="utf-8")  # noqa: SIM115  (closed below)
    process = subprocess.Popen(
        args, cwd=ROOT, env=env, stdout=out, stderr=subprocess.STDOUT, text=True
    )
    out.close()
    try:
        yield process
    finally:
        if process.poll() is None:
            process.send_signal(signal.SIGINT)
            try:
                process.wait(timeout=15)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait(timeout=15)


def _ros2(env: dict[str, str], *args: str, timeout: float = 20.0) -> str:
    assert ROS2 is not None
    try:
        done = subprocess.run(
            [ROS2, *args], env=env, capture_output=True, text=True, timeout=timeout
        )
    except subprocess.TimeoutExpired as exc:
        return str(exc.stdout or "")
    return done.stdout


def test_ros_2_tools_list_and_echo_the_cross_door_society(tmp_path: Path) -> None:
    port = free_port()
    router = endpoint(port)
    base = {**os.environ, "RMW_IMPLEMENTATION": "rmw_zenoh_cpp", "ROS_DOMAIN_ID": "0"}
    router_env = {**base, "ZENOH_CONFIG_OVERRIDE": f'listen/endpoints=["{router}"]'}
    tools = {**base, "ZENOH_CONFIG_OVERRIDE": f'connect/endpoints=["{router}"]'}
    assert ROS2 is not None
    with _started(
        [ROS2, "run", "rmw_zenoh_cpp", "rmw_zenohd"], router_env, tmp_path / "router.log"
    ):
        time.sleep(2.0)  # the router listening
        launch = [sys.executable, "-m", "cfgplan", "launch", *STEP1, "--impl", str(EXAMPLE_IMPL)]
        launch += ["--ros2", "--ros2-map", str(MAP), "--connect", router, "--duration", "120"]
        with _started(launch, {**os.environ, "PYTHONUNBUFFERED": "1"}, tmp_path / "launch.log"):
            wanted = {"/door_estimate", "/cfgplan/events", "/cfgplan/channel/pos/Pippi/Door1"}
            deadline, listed = time.monotonic() + LIMIT, set()
            while not wanted <= listed:
                assert time.monotonic() < deadline, f"ros2 topic list: {sorted(listed)}"
                listed = set(_ros2(tools, "topic", "list", "--no-daemon").split())
                time.sleep(1.0)
            pose = _ros2(tools, "topic", "echo", "--once", "/door_estimate", timeout=LIMIT)
            assert "frame_id: pippi/base_link" in pose and "position:" in pose, pose
            channel = _ros2(
                tools, "topic", "echo", "--once", "/cfgplan/channel/pos/Pippi/Door1", timeout=LIMIT
            )
            assert "data:" in channel and "Pippi" in channel, channel
