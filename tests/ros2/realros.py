"""Real ROS 2 (rclpy from the ros2-rclpy extra, or a sourced ROS 2) for the ``ros2`` test set.

Where rclpy cannot be imported the ``ros2`` tests are skipped, saying how to
get it; under CI (``CI=true``, where .ci/run installs it) a missing rclpy is
a failure, so a broken install step cannot pass as skipped tests. Each test
that starts nodes gets a ROS domain of its own (:func:`domain`) and
``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``: nodes of two tests, or of
another engineer's run, never meet.
"""

from __future__ import annotations

import importlib
import itertools
import os
import sys
from pathlib import Path
from types import ModuleType
from typing import Any

import pytest

INSTALL = "pip install -e '.[ros2-rclpy]' (then: pip uninstall lark-parser; see .ci/run)"
_domains = itertools.count((os.getpid() % 50) * 4 + 10)


def rclpy() -> ModuleType:
    """rclpy, or the test skipped (failed under CI)."""
    try:
        return importlib.import_module("rclpy")
    except ImportError as exc:
        if os.environ.get("CI") == "true":
            raise AssertionError(f"CI installs rclpy (.ci/run); it does not import: {exc}") from exc
        pytest.skip(f"no rclpy here ({exc}): {INSTALL}")


def message_class(msg_type: str) -> Any:
    """rclpy's class of ``pkg/msg/Name``."""
    package, _, name = msg_type.split("/")
    return getattr(importlib.import_module(f"{package}.msg"), name)


def share() -> Path:
    """Where the ROS 2 packages' ``share/<pkg>/msg/*.json`` type descriptions are."""
    prefixes = [*os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep), sys.prefix]
    for prefix in filter(None, prefixes):  # a sourced ROS 2's, else the wheels' (the venv)
        if (Path(prefix) / "share" / "std_msgs" / "msg").is_dir():
            return Path(prefix) / "share"
    raise AssertionError(f"no share/std_msgs/msg under {prefixes}")


def domain() -> int:
    """A ROS domain id for one test (distinct within this run; 10 to 229)."""
    return 10 + (next(_domains) - 10) % 220


def ros_env(domain_id: int) -> dict[str, str]:
    """The environment of a node process: this domain, localhost discovery only."""
    return {
        **os.environ,
        "ROS_DOMAIN_ID": str(domain_id),
        "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST",
        "PYTHONUNBUFFERED": "1",
    }
