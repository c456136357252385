"""``cfgplan simulate``: the outputs, determinism, exit codes and clear failures."""

from __future__ import annotations

import io
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest
from typer.testing import CliRunner

from cfgplan.cli import commands  # noqa: F401  (loads every command module)
from cfgplan.cli.app import app
from cfgplan.sim.run import open_scenario, simulate
from tests.sim.conftest import DATA, ROOT


def _run(*args: str) -> tuple[int, str, str]:
    result = CliRunner().invoke(app, ["simulate", *args])
    assert "Traceback" not in result.stdout + result.stderr
    return result.exit_code, result.stdout, result.stderr


def _scenario(tmp_path: Path, name: str, edit: tuple[str, str] | None = None) -> Path:
    """A copy of a bundled scenario next to its domain's files, edited."""
    source = ROOT / "domains" / name
    text = next(source.glob("sim-*.toml")).read_text("utf-8")
    text = text.replace('domain = "', f'domain = "{source}/').replace(
        'state = "', f'state = "{source}/'
    )
    if edit is not None:
        assert edit[0] in text, edit
        text = text.replace(*edit)
    path = tmp_path / f"{name}.toml"
    path.write_text(text, "utf-8")
    return path


@pytest.mark.slow
def test_outputs_and_the_same_bytes_for_the_same_seed(tmp_path: Path) -> None:
    """Fig. 6.5 and 6.6 as pictures, the configurations drawn, the summary and
    the trace: all byte for byte the same for one seed, another seed differs."""
    one, two = tmp_path / "one", tmp_path / "two"
    code, out, _ = _run("carry-bar", "--out", str(one))
    assert code == 0, out
    assert "33 -> 45" in out and "accomplished in" in out
    names = sorted(p.name for p in one.iterdir())
    assert names == [
        "bar.png",
        "configuration-1.png",
        "configuration-2.png",
        "summary.json",
        "timeline.png",
        "trace.jsonl",
        "trajectories.png",
    ]
    for name in names:
        data = (one / name).read_bytes()
        if name.endswith(".png"):
            assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 10_000, name
    summary = json.loads((one / "summary.json").read_text())
    assert [c["diagram"] for c in summary["configurations"]] == [
        "configuration-1.png",
        "configuration-2.png",
    ]
    trace = [json.loads(line) for line in (one / "trace.jsonl").read_text().splitlines()]
    switches = [e for e in trace if e["event"] == "switch"]
    assert [(e["from_cost"], e["to_cost"], e["t"]) for e in switches] == [
        (33, 45, summary["switches"][0]["time"])
    ]
    assert all("latency" not in e and "duration" not in e for e in trace)  # no wall clock
    # another process, with another hash seed (set orders differ): the same bytes
    env = {**os.environ, "PYTHONHASHSEED": "12345"}
    done = subprocess.run(
        [sys.executable, "-m", "cfgplan", "simulate", "carry-bar", "--out", str(two), "--quiet"],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 0, done.stderr
    for name in (
        "summary.json",
        "trace.jsonl",
        "trajectories.png",
        "timeline.png",
        "configuration-2.png",
    ):
        assert (one / name).read_bytes() == (two / name).read_bytes(), name
    other = io.StringIO()
    simulate(open_scenario("carry-bar"), seed=7, trace=other)
    assert (one / "trace.jsonl").read_text() != other.getvalue()


def test_animate_writes_a_gif(tmp_path: Path) -> None:
    code, _, _ = _run(
        "carry-bar", "--out", str(tmp_path), "--animate", "--duration", "2", "--quiet"
    )
    assert code == 4  # not delivered in 2 s, but drawn
    gif = (tmp_path / "animation.gif").read_bytes()
    assert gif[:6] == b"GIF89a" and len(gif) > 5_000


def test_existing_outputs_are_kept_without_force(tmp_path: Path) -> None:
    out = tmp_path / "out"
    out.mkdir()
    (out / "summary.json").write_text("mine")
    code, _, err = _run("carry-bar", "--out", str(out), "--quiet", "--duration", "1")
    assert code == 1 and "pass --force" in err
    assert (out / "summary.json").read_text() == "mine"
    code, _, _ = _run("carry-bar", "--out", str(out), "--quiet", "--duration", "1", "--force")
    assert code == 4  # 1 s is too short to deliver the bar
    assert (out / "summary.json").read_text() != "mine"


def test_a_scenario_that_fails_says_which_step_and_why(tmp_path: Path) -> None:
    # a bar that tolerates 2 cm: it falls, and the run says when and why
    tight = _scenario(tmp_path, "carry-bar", ("tolerance = 0.2", "tolerance = 0.02"))
    code, _, err = _run(str(tight), "--out", str(tmp_path / "out"), "--quiet")
    assert code == 4
    assert re.search(
        r"not accomplished: the bar fell at [\d.]+ s: Pippi and Emil were [\d.]+ m apart", err
    )
    assert "step 1, do-carry-bar(Pippi), was not accomplished" in err
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["success"] is False and summary["bar"]["dropped"] is True
    # out of time: what the action was waiting for, and why the data did not come
    short = _scenario(tmp_path, "cross-door", ("duration = 120.0", "duration = 5.0"))
    code, _, err = _run(str(short), "--out", str(tmp_path / "short"), "--quiet")
    assert code == 4
    assert "step 1, do-cross-door(Pippi, Door1), was not accomplished by 5 s (duration)" in err
    assert "Pippi ended in Room1, expected in Room2" in err


def test_no_configuration_exits_3_with_the_planners_reason(tmp_path: Path) -> None:
    code, _, err = _run("carry-bar", "--out", str(tmp_path / "out"), "--rank", "6", "--quiet")
    assert code == 3
    assert "do-carry-bar(Pippi) has 5 configurations, none of rank 6" in err
    # a goal nothing can reach: the planner's explanation, in the summary too
    nowhere = _scenario(
        tmp_path,
        "cross-door",
        ('impl = "cfgplan', 'goals = ["(do-cross-door Emil Door2)"]\nimpl = "cfgplan'),
    )
    code, _, err = _run(str(nowhere), "--out", str(tmp_path / "nowhere"), "--quiet")
    assert code == 3
    assert "step 1, do-cross-door(Emil, Door2), has no admissible configuration" in err
    assert "precondition: no fact matches (door Door2)" in err
    summary = json.loads((tmp_path / "nowhere" / "summary.json").read_text())
    assert summary["success"] is False and summary["ended"] == "none"
    assert any("(door Door2)" in line for line in summary["why"])


def test_bad_scenarios_are_errors_at_their_place(tmp_path: Path) -> None:
    cases = {
        ("at = [0.35, 0.35, 48]", "at = [0.35, 0.35]"): r"robots\.Emil\.at: too few values",
        ("width = 1.0", "widht = 1.0"): r"world\.doors\.Door1\.widht: unknown key",
        (
            "deflection = 70",
            'deflection = "a lot"',
        ): r"world\.magnetic\[0\]\.deflection: input should be a valid number",
        (
            "at = [0.35, 0.35, 48]",
            "at = [3.5, 0.35, 48]",
        ): r"robots\.Emil\.at: \(3\.5, 0\.35\) is in no room",
        ('name = "cross-door"', 'name = = "cross-door"'): r"not a scenario \(TOML\)",
        (
            "seed = 1",
            'seed = 1\nfaults = ["fail compass(Emil) at noon"]',
        ): r"faults\[0\]: 'fail compass\(Emil\) at noon': not a fault",
        (
            "seed = 1",
            'seed = 1\nfaults = ["kill Emli at 5s"]',
        ): r"faults\[0\]: 'kill Emli at 5s': no robot Emli in this society\n(.|\n)*"
        r"hint: did you mean Emil\?",
        (
            'impl = "cfgplan.sim.impl.cross_door"',
            'impl = "cfgplan.sim.impl.carry_bar"',
        ): r"impl: no implementation of functionalities camera",
        (
            "[robots.Pippi]",
            "[robots.Ada]\nat = [1, 1, 0]\n[robots.Pippi]",
        ): r"robots\.Ada: no \(robot Ada\) in the state",
        ('Pippi = "Room2"', 'Ada = "Room2"'): r"expect\.rooms\.Ada: no robot Ada in robots",
    }
    for edit, expected in cases.items():
        path = _scenario(tmp_path, "cross-door", edit)
        code, _, err = _run(str(path), "--out", str(tmp_path / "never"), "--quiet")
        assert code == 1, (edit, err)
        assert re.search(expected, err), (edit, err)
        # file:line:col, the line quoted, a caret under the key
        changed = edit[1].split("\n")[-1 if "faults" in edit[1] else 0]
        line = next(i for i, t in enumerate(path.read_text().splitlines(), 1) if changed in t)
        assert f"{path}:{line}:" in err, (edit, err)
        assert "^" in err
    assert not (tmp_path / "never").exists()  # nothing written for bad input
    code, _, err = _run("no-such-experiment", "--out", str(tmp_path / "x"))
    assert code == 1 and "cross-door, carry-bar, build-wall" in err
    code, _, _ = _run("carry-bar", "--out", str(tmp_path / "x"), "--duration", "-1")
    assert code == 2


def test_a_scenario_of_ones_own_beyond_the_thesis(tmp_path: Path) -> None:
    """README's example: a relay through two doors, a helper lost and back."""
    relay = ROOT / "examples" / "sim-relay" / "relay.toml"
    code, _, err = _run(str(relay), "--out", str(tmp_path / "relay"))
    assert code == 0, err
    summary = json.loads((tmp_path / "relay" / "summary.json").read_text())
    assert [(w["from_cost"], w["to_cost"]) for w in summary["switches"]] == [
        (44, None),
        (None, 44),
        (44, 47),
    ]
    assert summary["switches"][0]["reason"] == "Emil failed"
    assert summary["robots"]["Pippi"]["room"] == "Room3"
    assert [st["achieved"] for st in summary["steps"]] == [True, True]
    assert DATA.is_dir()


def test_without_the_sim_extra_it_says_what_to_install(monkeypatch: pytest.MonkeyPatch) -> None:
    import cfgplan.cli.simulate as command

    real = command.importlib.import_module

    def missing(name: str) -> object:
        if name == "shapely":
            raise ImportError(name)
        return real(name)

    monkeypatch.setattr(command.importlib, "import_module", missing)
    code, _, err = _run("carry-bar", "--out", "never")
    assert code == 1
    assert "cfgplan simulate needs shapely" in err and "pip install 'cfgplan[sim]'" in err
