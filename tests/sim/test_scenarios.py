"""The three experiments of chapter 6 replayed in the simulator: the numbers
each run must show (what the simulator was built to show).

* cross-door (6.2.2 steps 1-3, Figs. 6.4-6.6): Pippi crosses with Emil's
  help (44), Emil with Pippi's (44, roles exchanged); Emil's compass is
  disturbed on his way, *detected* (it disagrees with his odometry), and the
  society switches once, 44 -> 47; both end in Room2.
* carry-bar (6.3.2, Figs. 6.8, 6.9): the laser breaks, 33 -> 45, the bar
  never falls.
* build-wall (6.4, Figs. 6.11, 6.12): 53, then B1 hides W1's end from Emil's
  laser and Rasmus takes over (the three-robot configuration, 66); B1 ends
  aligned with W1.
"""

from __future__ import annotations

import math
from typing import Any

from cfgplan.sim.run import Run


def test_cross_door_two_steps_one_switch_44_to_47_after_the_disturbance(
    bundled: dict[str, Run], summaries: dict[str, Any]
) -> None:
    s = summaries["cross-door"]
    assert s["success"] is True, s["why"]
    steps = s["steps"]
    assert [st["goal"] for st in steps] == [
        "do-cross-door(Pippi, Door1)",
        "do-cross-door(Emil, Door1)",
    ]
    assert all(st["achieved"] for st in steps)
    first, second = steps[0]["time"], steps[1]["time"]
    assert 10 < first < second < 60
    # the step change, then exactly one reconfiguration: 44 -> 47
    changes = [(w["from_cost"], w["to_cost"]) for w in s["switches"]]
    assert changes == [(44, 44), (44, 47)]
    step_change, switch = s["switches"]
    assert step_change["reason"] == "next step: do-cross-door(Emil, Door1)"
    assert step_change["time"] == first
    assert switch["reason"] == "compass(Emil) failed" and switch["source"] == "fallback"
    # detected, not announced: the compass implementation saw its readings
    # disagree with the odometry, during Emil's crossing
    (fault,) = s["faults"]
    assert fault["resource"] == "compass(Emil)" and fault["how"] == "reported"
    assert "off the odometry's heading" in fault["detail"]
    assert fault["withdrawn"] == ["(compass Emil)"]
    assert first < fault["time"] == switch["time"] < second
    assert not s["injected"] and not s["world_changes"]
    # Emil was in the disturbance when it was detected
    run = bundled["cross-door"]
    sample = min(run.world.samples, key=lambda x: abs(x.t - fault["time"]))
    x, y, _ = sample.robots["Emil"]
    (field,) = run.loaded.scenario.world.magnetic
    assert math.hypot(x - field.at[0], y - field.at[1]) < 3 * field.radius
    # the configuration that carried Emil through: 47, both robots, Fig. 6.4 bottom
    last = s["configurations"][-1]
    assert last["cost"] == 47 and sorted(last["robots"]) == ["Emil", "Pippi"]
    assert any("measure-robot-orient-camera(Pippi, Emil)" in f for f in last["functionalities"])
    assert {r: v["room"] for r, v in s["robots"].items()} == {"Emil": "Room2", "Pippi": "Room2"}
    assert all(v["bumps"] == 0 for v in s["robots"].values())
    # the compass came back while Emil was in Room2, and the society stayed on 47 (no flapping)
    assert [r["resource"] for r in s["recoveries"]] == ["compass(Emil)"]


def test_carry_bar_switches_33_to_45_and_never_drops_the_bar(summaries: dict[str, Any]) -> None:
    s = summaries["carry-bar"]
    assert s["success"] is True, s["why"]
    assert s["world_changes"] == [{"time": 6.0, "what": "laser(Emil) breaks"}]
    (switch,) = s["switches"]
    assert (switch["from_cost"], switch["to_cost"]) == (33, 45)
    assert switch["reason"] == "laser(Emil) failed"
    assert 6.0 <= switch["time"] <= 6.3  # the next cycle's scan finds the laser silent
    (fault,) = s["faults"]
    assert fault["resource"] == "laser(Emil)" and "does not answer" in fault["detail"]
    bar = s["bar"]
    assert bar["dropped"] is False
    assert 1.0 < bar["min"] <= bar["max"] < 1.4  # 1.2 +- 0.2 all along
    assert bar["max"] - bar["min"] < 0.15
    costs = [c["cost"] for c in s["configurations"]]
    assert costs == [33, 45]
    assert {r: v["room"] for r, v in s["robots"].items()} == {"Pippi": "Room2", "Emil": "Room2"}
    (step,) = s["steps"]
    assert step["achieved"] and 15 < step["time"] < 40


def test_build_wall_rasmus_takes_over_when_b1_hides_w1_and_b1_is_aligned(
    summaries: dict[str, Any],
) -> None:
    s = summaries["build-wall"]
    assert s["success"] is True, s["why"]
    (switch,) = s["switches"]
    assert (switch["from_cost"], switch["to_cost"]) == (53, 66)
    assert switch["reason"] == "measure-pos-laser(Emil, W1) failed"
    (fault,) = s["faults"]
    assert "hidden behind B1" in fault["detail"]
    assert 1.0 < fault["time"] < 10.0  # while the block is being steered
    first, second = s["configurations"]
    assert sorted(first["robots"]) == ["Emil", "Pippi"]
    assert sorted(second["robots"]) == ["Emil", "Pippi", "Rasmus"]
    assert any(
        f.endswith("transform-block-data(Rasmus, B1, W1)") for f in second["functionalities"]
    )
    block = s["blocks"]["B1"]
    assert block["aligned"] is True and block["jams"] == 0
    assert abs(block["across"]) < 0.02 and abs(block["depth"]) < 0.02
    assert abs(block["turn_deg"]) < 1.5
    assert s["robots"]["Rasmus"]["distance"] == 0.0  # he watches, he does not move


def test_the_runs_are_fast_and_short(bundled: dict[str, Run]) -> None:
    """Simulated time, not wall time: each scenario ends when its task is done."""
    for name, run in bundled.items():
        assert run.ended == "achieved", name
        assert run.world.time < run.loaded.scenario.duration / 2, name
