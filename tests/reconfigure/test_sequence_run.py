"""Running a sequence of configurations (thesis 6.2.2 as one run).

``cfgplan run`` on the 6.2.2 sequence with the cross-door example (a crossing
takes ``CROSSING`` calls with data, then the action reports its task
accomplished): step 1's configuration runs until Pippi is through, its
postconditions are applied, step 2's configuration is installed (Pippi, now in
Room2, guides Emil) and runs until Emil is through; a failure during step 2
re-plans the steps left from the current state.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
RUN = [
    sys.executable,
    "-m",
    "cfgplan",
    "run",
    "domains/cross-door/domain-steps.lisp",
    "domains/cross-door/state-6.2.2-sequence.lisp",
    "--impl",
    "examples/cross-door/steps.py",
    "--rate",
    "0",
    "--cycles",
    "400",
]


def events(tmp_path: Path, *extra: str) -> list[dict[str, object]]:
    trace = tmp_path / "trace.jsonl"
    out = subprocess.run(
        [*RUN, "--trace", str(trace), *extra],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=300,
    )
    assert out.returncode == 0, out.stderr
    wanted = ("achieved", "switch", "failure", "no-configuration")
    return [e for e in map(json.loads, trace.read_text().splitlines()) if e["event"] in wanted]


def test_the_steps_run_one_after_the_other(tmp_path: Path) -> None:
    seen = events(tmp_path)
    assert [(e["event"], e.get("functionality"), e.get("to_cost")) for e in seen] == [
        ("achieved", "cross-door(Pippi, Door1)", None),
        ("switch", None, 44),
        ("achieved", "cross-door(Emil, Door1)", None),
    ]
    assert seen[1]["cause"] == "next step: do-cross-door(Emil, Door1)"
    started = seen[1]["started"]
    assert isinstance(started, dict)
    # Pippi, now in Room2, guides Emil; the compasses of both keep running.
    assert any("transform-info(Pippi, Emil, Door1)" in f for f in started["functionalities"])
    kept = seen[1]["kept"]
    assert isinstance(kept, dict)
    assert kept["functionalities"] == ["F10: compass(Pippi)", "F11: compass(Emil)"]


def test_a_failure_in_a_step_replans_the_steps_left(tmp_path: Path) -> None:
    seen = events(tmp_path, "--inject", "fail compass(Emil) at cycle 150")
    assert [(e["event"], e.get("to_cost")) for e in seen] == [
        ("achieved", None),
        ("switch", 44),
        ("failure", None),
        ("switch", 47),  # the camera configuration, Fig. 6.4 bottom
        ("achieved", None),
    ]
    assert seen[3]["cause"] == "compass(Emil) failed"
