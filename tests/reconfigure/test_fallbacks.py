"""``cfgplan plan --fallbacks``: the best configuration if one resource fails (5.5, 7.2).

Golden files, checked by eye against the thesis:

* ``fallbacks-cross-door-44.txt`` mirrors 6.2.2 step 3: a compass fails and
  the camera configuration of Fig. 6.4 (bottom, roles exchanged: 47) takes
  over; the action, the helper's camera and everything only one robot can do
  are single points of failure.
* ``fallbacks-carry-bar-33.txt`` mirrors 6.3.2: the laser fails and a 45
  configuration of Fig. 6.8 (bottom: both robots localize with sonars and
  odometry) takes over.
* ``fallbacks-build-wall-53.txt`` mirrors 6.4: when Emil cannot measure the
  wall (``measure-pos-laser(Emil, W1)``: "the block might occlude the wall")
  Rasmus takes over the block data, Fig. 6.12 (printed 67; its boxes and
  arrows count 66).
* ``fallbacks-cross-door-44-media.json`` is 4.6 with media: both sockets are
  single points of failure.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

import cfgplan.cli.commands  # noqa: F401  (loads every command module)
from cfgplan.cli.app import app
from tests.backends.support import ROOT, check_golden

DOMAINS = Path("domains")

CASES = {
    "fallbacks-cross-door-44.txt": ("cross-door/domain.lisp", "cross-door/state-6.2.2-step1.lisp"),
    "fallbacks-carry-bar-33.txt": ("carry-bar/domain.lisp", "carry-bar/state-6.3.2.lisp"),
    "fallbacks-build-wall-53.txt": ("build-wall/domain.lisp", "build-wall/state-6.4.lisp"),
}


@pytest.fixture(autouse=True)
def _at_the_root(monkeypatch: pytest.MonkeyPatch) -> None:
    """Relative paths, so that explanations quote ``domains/...`` as a user would."""
    monkeypatch.chdir(ROOT)


def _plan(*args: str) -> str:
    result = CliRunner().invoke(app, ["plan", *args])
    assert result.exit_code == 0, result.output
    return result.stdout


@pytest.mark.parametrize("golden", sorted(CASES))
def test_fallback_tables_match_the_golden_files(golden: str) -> None:
    domain, state = CASES[golden]
    check_golden(
        golden, _plan(str(DOMAINS / domain), str(DOMAINS / state), "-k", "1", "--fallbacks")
    )


def _fallbacks(domain: str, state: str) -> dict[str, dict[str, object]]:
    text = _plan(str(DOMAINS / domain), str(DOMAINS / state), "--format", "json", "--fallbacks")
    return {f["resource"]: f for f in json.loads(text)["fallbacks"]}


def test_cross_door_compass_falls_back_to_the_camera_configuration() -> None:
    found = _fallbacks(*CASES["fallbacks-cross-door-44.txt"])
    compass = found["compass(Emil)"]
    assert compass["cost"] == 47 and compass["withdrawn"] == ["(compass Emil)"]
    assert compass["stopped"] == [
        "measure-robot-orient-compass(Emil, Pippi)",
        "compass(Emil)",
        "compass(Pippi)",
    ]
    names = [f["name"] for f in compass["configuration"]["functionalities"]]  # type: ignore[index]
    assert "measure-robot-orient-camera" in names and "compass" not in names
    camera = found["camera(Emil)"]
    assert camera["cost"] is None and camera["configuration"] is None
    assert any("(camera Emil)" in line for line in camera["why"])  # type: ignore[union-attr]
    assert found["Emil"]["kind"] == "robot" and found["Emil"]["cost"] is None


def test_carry_bar_laser_falls_back_to_45() -> None:
    found = _fallbacks(*CASES["fallbacks-carry-bar-33.txt"])
    assert found["laser(Emil)"]["cost"] == 45
    assert found["laser(Emil)"]["withdrawn"] == ["(laser Emil)"]
    assert [r for r, f in found.items() if f["cost"] is None] == ["Pippi", "Emil"]


def test_build_wall_without_the_wall_measure_is_fig_6_12() -> None:
    found = _fallbacks(*CASES["fallbacks-build-wall-53.txt"])
    fig = found["measure-pos-laser(Emil, W1)"]
    assert fig["cost"] == 66 and fig["robots"] == ["Emil", "Pippi", "Rasmus"]
    assert fig["stopped"] == [
        "transform-block-data(Emil, B1, W1)",
        "measure-orient-laser(Emil, W1)",
        "measure-pos-laser(Emil, W1)",
        "measure-pos-laser(Emil, B1)",
    ]


def test_media_are_resources_and_the_json_is_golden() -> None:
    text = _plan(
        str(DOMAINS / "cross-door/domain-bandwidth.lisp"),
        str(DOMAINS / "cross-door/state-4.6-media.lisp"),
        "-k",
        "1",
        "--format",
        "json",
        "--fallbacks",
    )
    check_golden("fallbacks-cross-door-44-media.json", text)
    media = [f for f in json.loads(text)["fallbacks"] if f["kind"] == "medium"]
    assert [m["resource"] for m in media] == [
        "medium(socket, Pippi, Emil, 200)",
        "medium(socket, Emil, Pippi, 200)",
    ]
    assert all(m["cost"] is None for m in media)


def test_lisp_format_lists_fallbacks_as_comments() -> None:
    domain, state = CASES["fallbacks-carry-bar-33.txt"]
    text = _plan(
        str(DOMAINS / domain), str(DOMAINS / state), "-k", "1", "--format", "lisp", "--fallbacks"
    )
    assert (
        ";;   functionality laser(Emil): cost 45 (withdraws (laser Emil); stop 2, start 7)" in text
    )
    assert text.rstrip().endswith(";; single points of failure (2): Pippi, Emil")


def test_without_the_option_the_json_has_no_fallbacks() -> None:
    domain, state = CASES["fallbacks-carry-bar-33.txt"]
    text = _plan(str(DOMAINS / domain), str(DOMAINS / state), "--format", "json")
    assert "fallbacks" not in json.loads(text)
