"""The ROS 2 example (examples/cross-door/ros2-map.toml) end to end:
cross-door over ROS 2 topics, in one command (slow).

``cfgplan launch`` starts cross-door step 1 (Pippi crosses, Emil helps) with
examples/cross-door/ros2-map.toml and ``--ros2``. The test's ROS side, a
plain zenoh-python session written from rmw_zenoh's design document (the key
expressions spelled out here, the CDR read by rosbags), must receive Emil's
door estimate as a ``geometry_msgs/msg/PoseStamped`` whose numbers are those
Emil's transform-info computed (his trace), and the global channel
``pos(Pippi, Door1)`` on ``/cfgplan/channel/pos/Pippi/Door1``; Pippi's
cross-door must run on the topic (her summary: messages given to calls).
Then the fault: Emil, the topic's publisher, is frozen (SIGSTOP) past his
lease and let go (SIGCONT). What the society does is asserted: Pippi's
coordinator reports Emil lost (not her action failing: its channel goes stale
before the topic's timeout, so cross-door is not called), the crossing waits,
and after Emil runs again the estimate flows again on the same publisher
(sequence numbers go on) and cross-door runs on it again. SIGTERM to the
launch stops both robots: exit 0, every pid gone. Hermetic: loopback, free
ports, scouting off, bounded waits.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import re
import signal
import struct
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from tests.backends.support import DOMAINS, EXAMPLE_IMPL, ROOT
from tests.runtime.netutil import (
    Record,
    endpoint,
    free_port,
    hermetic_config,
    read_trace,
    wait_for,
)

zenoh = pytest.importorskip("zenoh")
typesys = pytest.importorskip("rosbags.typesys")

STORE = typesys.get_typestore(typesys.Stores.ROS2_JAZZY)
POSE = "geometry_msgs/msg/PoseStamped"
POSE_KEY = "0/door_estimate/geometry_msgs::msg::dds_::PoseStamped_/" + STORE.hash_rihs01(POSE)
STRING_HASH = "RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18"
CHANNEL_KEY = f"0/cfgplan/channel/pos/Pippi/Door1/std_msgs::msg::dds_::String_/{STRING_HASH}"
"""design.md: <domain_id>/<fully qualified name>/<type name>/<type hash>."""
MAP = ROOT / "examples" / "cross-door" / "ros2-map.toml"
STEP1 = [
    str(DOMAINS / "cross-door/domain.lisp"),
    str(DOMAINS / "cross-door/state-6.2.2-step1.lisp"),
]
LIMIT = 90.0  # seconds: two interpreters, a Zenoh handshake and a run, on a loaded machine
FROZEN = 3.0  # seconds: past the 1 s lease


class RosSide:
    """A ROS 2 subscriber of /door_estimate and of a channel topic, from plain zenoh-python."""

    def __init__(self, config: Path, port: int) -> None:
        conf = zenoh.Config.from_file(str(config))
        conf.insert_json5("mode", '"peer"')
        conf.insert_json5("listen/endpoints", json.dumps([endpoint(port)]))
        self.session = zenoh.open(conf)
        self.lock = threading.Lock()
        self.poses: list[tuple[float, Any, int]] = []  # arrival, message, sequence number
        self.channel: list[dict[str, Any]] = []
        self.tokens: set[str] = set()
        self.session.declare_subscriber(POSE_KEY, self.on_pose)
        self.session.declare_subscriber(CHANNEL_KEY, self.on_channel)
        self.session.liveliness().declare_subscriber("@ros2_lv/0/**", self.on_token, history=True)

    def on_pose(self, sample: Any) -> None:
        payload = sample.payload.to_bytes()
        assert payload[:4] == b"\x00\x01\x00\x00"
        message = STORE.deserialize_cdr(payload, POSE)
        extra = sample.attachment.to_bytes()
        assert len(extra) == 33 and extra[16] == 16
        with self.lock:
            self.poses.append((time.time(), message, struct.unpack_from("<q", extra)[0]))

    def on_channel(self, sample: Any) -> None:
        text = STORE.deserialize_cdr(sample.payload.to_bytes(), "std_msgs/msg/String").data
        with self.lock:
            self.channel.append(json.loads(text))

    def on_token(self, sample: Any) -> None:
        with self.lock:
            self.tokens.add(str(sample.key_expr))

    def received(self) -> list[tuple[float, Any, int]]:
        with self.lock:
            return list(self.poses)


def _yaw(message: Any) -> float:
    q = message.pose.orientation
    return math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))


def _pids(log: Path) -> dict[str, int]:
    text = log.read_text() if log.exists() else ""
    return {m[1]: int(m[2]) for m in re.finditer(r"^(\w+)\s*\| \(started: pid (\d+)\)", text, re.M)}


def _calls(trace: Path, name: str, after: float = 0.0) -> list[dict[str, Any]]:
    return [
        r
        for r in read_trace(trace)
        if r["event"] == "call" and r["functionality"] == name and r["status"] == "ran"
        and float(r["t"]) > after  # type: ignore[arg-type]
    ]  # fmt: skip


def _failure(trace: Path, resource: str, after: float) -> Callable[[], Record | None]:
    """A ``found`` for :func:`wait_for`: the failure of ``resource`` after ``after``."""

    def look() -> Record | None:
        for r in read_trace(trace):
            t = float(r["t"])  # type: ignore[arg-type]
            if r["event"] == "failure" and r["resource"] == resource and t > after:
                return r
        return None

    return look


@pytest.mark.slow
def test_the_cross_door_society_meets_ros_2_in_one_command(tmp_path: Path) -> None:
    config, port = hermetic_config(tmp_path), free_port()
    side = RosSide(config, port)
    log, trace = tmp_path / "launch.log", tmp_path / "run.jsonl"
    args = [sys.executable, "-m", "cfgplan", "launch", *STEP1, "--impl", str(EXAMPLE_IMPL)]
    args += ["--ros2-map", str(MAP), "--ros2", "--connect", endpoint(port), "--rate", "20"]
    args += ["--lease", "1", "--zenoh-config", str(config), "--duration", "150"]
    args += ["--trace", str(trace), "--society", f"ros2-cross-{tmp_path.name}"]
    emil_trace, pippi_trace = tmp_path / "run-emil.jsonl", tmp_path / "run-pippi.jsonl"
    out = open(log, "w", encoding="utf-8")  # noqa: SIM115  (closed below)
    launched = subprocess.Popen(
        args, cwd=ROOT, stdout=out, stderr=subprocess.STDOUT, text=True,
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
    )  # fmt: skip
    out.close()
    pids: dict[str, int] = {}
    try:
        pids = wait_for(
            "both robots started",
            lambda: got if len(got := _pids(log)) == 2 else None,  # type: ignore[arg-type,return-value]
            LIMIT,
        )
        wait_for(
            "five door estimates on /door_estimate",
            lambda: {"n": 5} if len(side.received()) >= 5 else None,
            LIMIT,
        )
        wait_for(
            "cross-door run on the topic",
            lambda: {"ok": 1} if _calls(pippi_trace, "cross-door") else None,
            LIMIT,
        )
        # the numbers are those Emil's transform-info computed: (orient, pos) in :out order
        computed = _calls(emil_trace, "transform-info")[-1]["outputs"]
        orient, pos = computed[0]["value"], computed[1]["value"]
        _, pose, _ = side.received()[-1]
        assert (pose.pose.position.x, pose.pose.position.y, pose.pose.position.z) == (*pos, 0.0)
        assert math.isclose(_yaw(pose), orient, abs_tol=1e-12)
        assert pose.header.frame_id == "pippi/base_link"
        assert abs(pose.header.stamp.sec - time.time()) < 60
        # the global channel pos(Pippi, Door1) as a topic, JSON in a String
        wait_for("the channel topic", lambda: {"ok": 1} if side.channel else None, LIMIT)
        assert side.channel[-1]["value"] == pos and side.channel[-1]["to"] == "Pippi"
        with side.lock:
            tokens = set(side.tokens)
        assert any("/MS/%/%/cfgplan_Pippi_topics/%door_estimate/" in t for t in tokens)
        assert any("/MP/%/%/cfgplan_Emil_topics/%door_estimate/" in t for t in tokens)

        # the fault: the topic's publisher frozen past its lease, then let go
        stopped = time.time()
        last_number = side.received()[-1][2]
        os.kill(pids["Emil"], signal.SIGSTOP)
        try:
            lost = wait_for("Emil lost", _failure(pippi_trace, "Emil", stopped), LIMIT)
            time.sleep(max(0.0, stopped + FROZEN - time.time()))
        finally:
            os.kill(pids["Emil"], signal.SIGCONT)
        let_go = time.time()
        assert lost["how"] == "lost"
        again = wait_for(
            "cross-door again",
            lambda: {"r": c[0]} if (c := _calls(pippi_trace, "cross-door", let_go)) else None,
            LIMIT,
        )["r"]
        after = [(n, p) for t, p, n in side.received() if t > let_go]
        assert after, "no door estimate after Emil ran again"
        assert after[0][0] > last_number  # the same publisher, its sequence goes on
        assert (after[-1][1].pose.position.x, after[-1][1].pose.position.y) == tuple(pos)
        assert again["status"] == "ran"
        launched.send_signal(signal.SIGTERM)
        assert launched.wait(timeout=LIMIT) == 0, log.read_text()
    finally:
        if launched.poll() is None:  # a failure: the launch and its robots killed, by pid
            launched.kill()
            launched.wait(timeout=30)
            for pid in pids.values():
                with contextlib.suppress(ProcessLookupError):
                    os.kill(pid, signal.SIGCONT)
                    os.kill(pid, signal.SIGKILL)
        side.session.close()
    text = log.read_text()
    for name, pid in pids.items():
        with pytest.raises(ProcessLookupError):
            os.kill(pid, 0)
        assert "Traceback" not in text, name
    # the topic, not the channel, failed nobody: only Emil was lost
    failed = [r["resource"] for r in read_trace(pippi_trace) if r["event"] == "failure"]
    assert set(failed) == {"Emil"}, failed
    summary = r"Pippi \| ros2: Pippi /door_estimate .*: \d+ messages received, given to (\d+) calls"
    given = re.search(summary, text)
    assert given is not None and int(given[1]) > 0, text[-3000:]
    assert re.search(r"Emil  \| ros2: Emil /door_estimate .*: (\d+) messages published", text)
