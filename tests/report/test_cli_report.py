"""``cfgplan report``: a simulation's trace, a ``cfgplan run`` trace with an
injected failure, its MCAP recording, and clear errors for anything else."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import pytest
from typer.testing import CliRunner

from cfgplan.cli import commands  # noqa: F401  (loads every command module)
from cfgplan.cli.app import app
from cfgplan.report.source import read_run
from cfgplan.report.story import from_records
from tests.backends.support import CROSS, DOMAINS, EXAMPLE_IMPL, ROOT


def _report(*args: str) -> tuple[int, str]:
    result = CliRunner().invoke(app, ["report", *args])
    text = result.stdout + result.stderr
    assert "Traceback" not in text
    return result.exit_code, text


def _svgs(page: str) -> int:
    return len(re.findall(r"<svg\b", page))


@pytest.mark.parametrize(
    ("content", "says"),
    [
        (b"", "no trace events"),
        (b"\n\n", "no trace events"),
        (b'{"a": 1}\n', 'bad.jsonl:1:1: error: not a trace event: it has no "event"'),
        (b"# a README\n", "bad.jsonl:1:1: error: not JSON"),
        (b'{"event": "switch", "robot": "P", "t": 1, "cycle": 1}\n', "not a trace event (switch)"),
        (b"\x89MCAP0\r\n\x00\x00garbage", "is not a readable MCAP recording"),
    ],
)
def test_bad_input_is_a_clear_error(tmp_path: Path, content: bytes, says: str) -> None:
    """Not a trace, empty, damaged: one clear line naming the file, exit 1, nothing drawn."""
    bad = tmp_path / "bad.jsonl"
    bad.write_bytes(content)
    code, text = _report(str(bad), "-o", str(tmp_path / "out"))
    assert code == 1, text
    assert says in text
    assert not (tmp_path / "out" / "report.html").exists()


def test_missing_files_folders_and_usage(tmp_path: Path) -> None:
    """A missing file and a folder without trace.jsonl: exit 1; no RUN: usage, exit 2."""
    code, text = _report(str(tmp_path / "nope.jsonl"), "-o", str(tmp_path / "out"))
    assert code == 1 and "no such file" in text
    code, text = _report(str(tmp_path), "-o", str(tmp_path / "out"))
    assert code == 1 and "trace.jsonl" in text
    code, text = _report("-o", str(tmp_path / "out"))
    assert code == 2 and "Missing argument" in text


def _simulate(folder: Path, name: str = "cross-door") -> None:
    result = CliRunner().invoke(app, ["simulate", name, "--out", str(folder), "--quiet"])
    assert result.exit_code == 0, result.stdout + result.stderr


@pytest.mark.slow
def test_a_simulations_trace_is_reported_with_its_trajectories(tmp_path: Path) -> None:
    """cross-door's trace.jsonl: the same three configurations as the simulation's
    summary, both switches and the compass's failure and recovery in the page;
    the simulation replayed for the trajectories; an edited trace is not replayed."""
    sim = tmp_path / "sim"
    _simulate(sim)
    out = tmp_path / "report"
    code, text = _report(str(sim / "trace.jsonl"), "-o", str(out))
    assert code == 0, text
    names = sorted(p.name for p in out.iterdir())
    assert names == [
        "configuration-1.png",
        "configuration-2.png",
        "configuration-3.png",
        "report.html",
        "timeline.png",
        "trajectories.png",
    ]
    summary = json.loads((sim / "summary.json").read_text("utf-8"))
    story = from_records(read_run([sim / "trace.jsonl"]).records, summary)
    assert [(s.number, s.config.cost, s.start) for s in story.spans] == [
        (c["diagram"] and int(c["diagram"][14:-4]), c["cost"], c["from"])
        for c in summary["configurations"]
    ]
    assert [m.t for m in story.of("switch")] == [s["time"] for s in summary["switches"]]
    page = (out / "report.html").read_text("utf-8")
    assert "44 → 47: compass(Emil) failed" in page and "compass(Emil) works again" in page
    assert _svgs(page) == 1 + 3 + 1  # the timeline, three diagrams, the trajectories
    assert not re.findall(r'(?:href|src)="(?!#)', page)  # nothing to fetch, links inside
    assert "<script" not in page and "<link" not in page
    # edited: one event less; the report is still drawn, without trajectories
    lines = (sim / "trace.jsonl").read_text("utf-8").splitlines(keepends=True)
    (sim / "trace.jsonl").write_text("".join(lines[:-1]), "utf-8")
    code, text = _report(str(sim), "-o", str(out), "--force")
    assert code == 0 and "No trajectories: simulating cross-door again" in text
    assert "trajectories.png" not in text.split("wrote")[-1]
    assert 'id="trajectories"' not in (out / "report.html").read_text("utf-8")


@pytest.mark.slow
def test_carry_bar_reports_the_bar_length(tmp_path: Path) -> None:
    """A simulation with a bar: bar.png and its picture in the page."""
    sim = tmp_path / "sim"
    _simulate(sim, "carry-bar")
    code, text = _report(str(sim), "-o", str(tmp_path / "r"))
    assert code == 0 and "bar.png" in text
    assert 'id="bar"' in (tmp_path / "r" / "report.html").read_text("utf-8")


def run_trace(folder: Path) -> Path:
    """A cfgplan run of cross-door (one process) with Emil's compass failing at cycle 40."""
    trace = folder / "run.jsonl"
    domain, state = CROSS
    args = [sys.executable, "-m", "cfgplan", "run", str(DOMAINS / domain), str(DOMAINS / state)]
    args += ["--impl", str(EXAMPLE_IMPL), "--cycles", "80", "--rate", "40", "--trace", str(trace)]
    args += ["--inject", "fail compass(Emil) at cycle 40"]
    done = subprocess.run(args, cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stdout + done.stderr
    return trace


@pytest.mark.slow
def test_a_run_trace_and_its_recording_are_reported(tmp_path: Path) -> None:
    """cfgplan run with an injected compass failure: two configurations (44, then
    47 from 40 cycles on), the switch's cause, the failure on Emil's row; the
    MCAP recording of that trace gives the same story and the same pictures."""
    trace = run_trace(tmp_path)
    out = tmp_path / "report"
    code, text = _report(str(trace), "-o", str(out))
    assert code == 0, text
    assert sorted(p.name for p in out.iterdir()) == [
        "configuration-1.png",
        "configuration-2.png",
        "report.html",
        "timeline.png",
    ]
    story = from_records(read_run([trace]).records)
    assert [(s.number, s.config.cost) for s in story.spans] == [(1, 44), (2, 47)]
    (switch,) = story.of("switch")
    assert switch.text == "44 → 47: compass(Emil) failed"
    assert 40 / 40 * 0.8 < switch.t < 40 / 40 * 3  # cycle 40 at 40 Hz: about 1 s in
    (failure,) = story.of("failure")
    assert (failure.robot, failure.record["how"]) == ("Emil", "injected")
    page = (out / "report.html").read_text("utf-8")
    assert "compass(Emil) failed" in page and _svgs(page) == 3
    recording = tmp_path / "run.mcap"
    result = CliRunner().invoke(app, ["record", str(trace), "-o", str(recording)])
    assert result.exit_code == 0, result.stdout
    again = tmp_path / "from-mcap"
    code, text = _report(str(recording), "-o", str(again))
    assert code == 0, text
    other = from_records(read_run([recording]).records)
    assert other.spans == story.spans and other.marks == story.marks
    # A chunk damaged inside (its compressed bytes flipped): its decompressor
    # fails, said as a clear error (before: a zstandard traceback).
    data = bytearray(recording.read_bytes())
    middle = len(data) // 2
    data[middle : middle + 8] = bytes(b ^ 0xFF for b in data[middle : middle + 8])
    damaged = tmp_path / "damaged.mcap"
    damaged.write_bytes(bytes(data))
    code, text = _report(str(damaged), "-o", str(tmp_path / "none"))
    assert code == 1 and "is not a readable MCAP recording" in text, text
    assert (again / "timeline.png").read_bytes() == (out / "timeline.png").read_bytes()


def test_an_earlier_report_is_kept_without_force(tmp_path: Path) -> None:
    """DIR holding report.html: refused (exit 1) unless --force."""
    trace = tmp_path / "t.jsonl"
    trace.write_text(
        '{"event":"start","robot":"Pippi","t":0.0,"cycle":0,"transport":"x",'
        '"partners":[],"rate":10.0}\n',
        "utf-8",
    )
    out = tmp_path / "out"
    out.mkdir()
    (out / "report.html").write_text("mine", "utf-8")
    code, text = _report(str(trace), "-o", str(out))
    assert code == 1 and "pass --force" in text
    assert (out / "report.html").read_text("utf-8") == "mine"
    code, text = _report(str(trace), "-o", str(out), "--force")
    assert code == 0, text
    assert "Robots: Pippi" in (out / "report.html").read_text("utf-8")


def test_a_run_that_never_switched_names_its_cost_and_is_drawn_beside_its_trace(
    tmp_path: Path,
) -> None:
    """The configuration a run started with is drawn with its cost (cross-door's
    step 3 has only the camera one, 47), taken from the robots' start events: a
    run that never switched has no switch event to read it from, and the report
    said "cost 0". Without -o the report goes beside the trace (run-report/)."""
    trace = tmp_path / "run.jsonl"
    domain = DOMAINS / "cross-door" / "domain.lisp"
    state = DOMAINS / "cross-door" / "state-6.2.2-step3.lisp"
    args = ["run", str(domain), str(state), "--impl", str(EXAMPLE_IMPL), "--cycles", "3"]
    result = CliRunner().invoke(app, [*args, "--rate", "50", "--trace", str(trace)])
    assert result.exit_code == 0, result.stdout + result.stderr
    starts = [json.loads(line) for line in trace.read_text("utf-8").splitlines()]
    assert {r["cost"] for r in starts if r["event"] == "start"} == {47}
    story = from_records(read_run([trace]).records)
    assert [(s.number, s.config.cost) for s in story.spans] == [(1, 47)]
    code, text = _report(str(trace))
    assert code == 0, text
    assert f"in {tmp_path / 'run-report'}" in text
    page = (tmp_path / "run-report" / "report.html").read_text("utf-8")
    assert "#1</a></td><td>47</td>" in page
    # A trace of emitted programs, which do not know the cost: "?", not 0.
    unknown = tmp_path / "emitted.jsonl"
    unknown.write_text(
        "".join(
            json.dumps({k: v for k, v in r.items() if k != "cost"}) + "\n"
            for r in starts
            if r["event"] != "switch"
        ),
        "utf-8",
    )
    code, text = _report(str(unknown), "-o", str(tmp_path / "u"))
    assert code == 0, text
    assert "#1</a></td><td>?</td>" in (tmp_path / "u" / "report.html").read_text("utf-8")
