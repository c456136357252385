"""The scale benchmark (benchmarks/scale.py): the helper it kills is the one in
use, its findings are said from its own figures, and the committed page is what
``--markdown`` writes. Nothing here is timed or started: the benchmark itself
runs the society."""

from __future__ import annotations

from pathlib import Path

from benchmarks.reconfigure import ROOT
from benchmarks.scale import KEYED, KILL_HEADER, START_HEADER, Row, findings, in_use, kill_cells


def test_the_helper_in_use_is_the_last_switchs_else_the_starts_partner() -> None:
    start = {"event": "start", "partners": ["Vacu", "H1"]}
    assert in_use([start]) == "H1"
    switch = {
        "event": "switch",
        "started": {"functionalities": ["F8: laser(H12)", "F9: scan-match(H12, Vacu)"]},
    }
    assert in_use([start, {"event": "call"}, switch]) == "H12"
    stop = {"event": "switch", "started": {"functionalities": []}}  # nothing started: look back
    assert in_use([start, switch, stop]) == "H12"
    assert in_use([{"event": "start", "partners": ["Vacu"]}]) is None
    assert in_use([]) is None


def test_the_findings_say_the_ratio_and_the_verdict_from_the_figures() -> None:
    small = Row(3, "router", connections=3, up=2.0, switches=[0.010, 0.012, 0.011])
    fast = Row(50, "router", connections=50, up=9.5, switches=[0.022, 0.022])
    slow = Row(50, "router", connections=50, up=12.0, switches=[0.030])
    said = findings([small, fast])
    assert "2.0× the" in said and "within the goal of 2×" in said
    assert "All 50 up** after 9.5 s (started together): within" in said
    said = findings([small, slow])
    assert "2.7× the" in said and "over the goal of 2×" in said
    assert "after 12.0 s (started together): over" in said
    assert kill_cells(slow, [small, slow])[7] == "2.7×"
    assert kill_cells(small, [slow])[7] == "-"  # no society of 3 to compare with


def test_the_keys_rows_are_said_against_the_rows_without_keys() -> None:
    """Behind the secured router: its connections and idle traffic, and each
    size's switch and start-up against the same size's without keys."""
    plain = [
        Row(3, "router", up=2.0, switches=[0.010]),
        Row(50, "router", up=10.0, switches=[0.030]),
    ]
    keyed = [
        Row(3, KEYED, connections=3, up=2.5, idle_segments=60, switches=[0.015]),
        Row(50, KEYED, connections=50, up=12.0, idle_segments=500, switches=[0.045]),
    ]
    said = findings([*plain, *keyed])
    assert "- **With keys**, through the secured router: connections 3 at 3, 50 at 50" in said
    assert "idle TCP segments a second per robot 20.0 at 3, 10.0 at 50" in said
    assert "a switch took 1.5× at 3, 1.5× at 50 the one without keys" in said
    assert "all up after 2.5 s against 2.0 s at 3, 12.0 s against 10.0 s at 50" in said
    assert "a switch among 50 3.0× the one among 3" in said
    assert "With keys" not in findings(plain)


def test_the_committed_page_was_written_by_the_benchmark() -> None:
    text = (ROOT / "docs" / "explanation" / "scale.md").read_text(encoding="utf-8")
    assert text.startswith("<!-- Written by `python -m benchmarks.scale")
    assert "| " + " | ".join(START_HEADER) + " |" in text
    assert "| " + " | ".join(KILL_HEADER) + " |" in text
    assert "- machine: " in text and "Made with `python -m benchmarks.scale" in text
    for n in (2, 5, 10, 20, 50):
        assert f"\n| {n} | router |" in text, n
    for n in (3, 50):  # with the society's keys, through its secured router
        assert f"\n| {n} | {KEYED} |" in text, n


def test_a_page_written_again_keeps_its_runs_facts_tables_and_findings(tmp_path: Path) -> None:
    """``--rewrite PAGE`` changes only the words around a run: the page it
    writes from a page the benchmark wrote is that page, byte for byte."""
    from benchmarks.reconfigure import table
    from benchmarks.scale import PROGRAM_HEADER, Options, page, rewrite, start_cells

    rows = [
        Row(3, "router", connections=3, up=2.0, switches=[0.010]),
        Row(3, "mesh", connections=3, up=2.5, switches=[0.012]),
        Row(50, "router", connections=50, up=9.0, switches=[0.020]),
    ]
    tables = [
        table(START_HEADER, [start_cells(r) for r in rows]),
        table(KILL_HEADER, [kill_cells(r, rows) for r in rows]),
        table(PROGRAM_HEADER, [["h1.py", "0.10 s", "35 MB"]]),
    ]
    shown = f"python -m benchmarks.scale --kills 5 --markdown {tmp_path / 'scale.md'}"
    text = page(shown, Options(kills=5), "- machine: here\n- date: now", tables, findings(rows))
    path = tmp_path / "scale.md"
    path.write_text(text, encoding="utf-8")
    rewrite(path)
    assert path.read_text(encoding="utf-8") == text
    assert "killed (SIGKILL) 5 times" in " ".join(text.split())
