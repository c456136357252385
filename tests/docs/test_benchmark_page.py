"""docs/explanation/benchmarks.md is the page ``python -m benchmarks.run --markdown``
writes: the run's facts, its table, and the command that made it."""

from __future__ import annotations

import re
from pathlib import Path

from benchmarks.page import page, write

ROOT = Path(__file__).resolve().parents[2]
TABLE = ["| instance | best |", "|---|---|", "| cross-door 6.2.2 | 44 |"]


def test_page_has_the_facts_the_table_and_how_to_regenerate(tmp_path: Path) -> None:
    command = ["--only", "cross-door", "--note", "loaded", "--markdown", "x.md"]
    write(tmp_path / "b.md", TABLE, "Linux x86_64, 2 cores", command, "loaded")
    text = (tmp_path / "b.md").read_text(encoding="utf-8")
    assert "\n".join(TABLE) in text
    assert "- machine: Linux x86_64, 2 cores" in text
    assert re.search(r"- date: \d{4}-\d\d-\d\d \d\d:\d\d UTC", text)
    assert re.search(r"- revision: `[0-9a-f]{7,}(-dirty)?`", text)
    assert "- note: loaded" in text
    # the note is shown apart, not in the command to run again
    assert "`python -m benchmarks.run --only cross-door --markdown x.md`" in text


def test_the_committed_page_was_written_by_the_script() -> None:
    text = (ROOT / "docs" / "explanation" / "benchmarks.md").read_text(encoding="utf-8")
    assert text.startswith("<!-- Written by `python -m benchmarks.run --markdown")
    assert "| instance | configs |" in text
    assert "Made with `python -m benchmarks.run" in text
    assert page(TABLE, "m", []).count("# Benchmarks") == 1
