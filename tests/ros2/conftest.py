"""The rmw_zenoh layout's tests speak it whether or not rclpy is installed here.

Where rclpy can be imported, ``--ros2`` and ``--ros2-map`` speak ROS 2
through it by default (:func:`cfgplan.ros2.node.choose_via`); the tests of
the pure-Python layout pin ``CFGPLAN_ROS2_VIA=zenoh`` (their robot processes
inherit it, through ``cfgplan launch`` too). The ``ros2`` set's tests choose
for themselves.
"""

from __future__ import annotations

import pytest

from cfgplan.ros2.node import VIA_ENV


@pytest.fixture(autouse=True)
def _zenoh_layout(request: pytest.FixtureRequest, monkeypatch: pytest.MonkeyPatch) -> None:
    if request.node.get_closest_marker("ros2") is None:
        monkeypatch.setenv(VIA_ENV, "zenoh")
