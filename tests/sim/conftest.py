"""Simulations shared by the tests of this package: each bundled scenario is
run once per session (a second or two each), without pictures."""

from __future__ import annotations

from pathlib import Path

import pytest

from cfgplan.sim.report import summary
from cfgplan.sim.run import Run, open_scenario, simulate

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / "tests" / "data" / "sim"


@pytest.fixture(scope="session")
def bundled() -> dict[str, Run]:
    """The three bundled scenarios, run with their own seed."""
    return {
        name: simulate(open_scenario(name)) for name in ("cross-door", "carry-bar", "build-wall")
    }


@pytest.fixture(scope="session")
def summaries(bundled: dict[str, Run]) -> dict[str, dict[str, object]]:
    return {name: summary(run) for name, run in bundled.items()}
