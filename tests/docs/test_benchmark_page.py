"""docs/explanation/benchmarks.md is the page ``python -m benchmarks.run --markdown``
writes: the run's facts, its table, and the command that made it."""

from __future__ import annotations

import re
from pathlib import Path

from benchmarks.page import instructions_page, page, rewrite, write

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


def test_the_instruction_page_says_how_it_was_counted_and_against_what() -> None:
    """docs/explanation/instructions.md is what ``python -m
    benchmarks.instructions --markdown`` writes: the table of counts beside
    the baseline revision, and the command to count again."""
    table = ["| instance | M instructions 6332e93 | M instructions now | now / then |"]
    made = instructions_page(table, "m", ["--against", "6332e93", "--markdown", "x.md"])
    assert made.startswith("<!-- Written by `python -m benchmarks.instructions --markdown")
    assert table[0] in made
    assert "`python -m benchmarks.instructions --against 6332e93 --markdown x.md`" in made
    text = (ROOT / "docs" / "explanation" / "instructions.md").read_text(encoding="utf-8")
    assert text.startswith("<!-- Written by `python -m benchmarks.instructions --markdown")
    assert "| instance | M instructions 6332e93 | M instructions now | now / then |" in text


def test_the_table_is_split_to_fit_the_content_column_and_the_load_is_said(
    tmp_path: Path,
) -> None:
    """The 12-column table overflowed the site's content column: planning times,
    then what the whole process takes, each with the instance; the page says the
    machine's load; ``python -m benchmarks.page`` rewrites a page's words
    without measuring, its figures kept."""
    head = "| instance | configs | top-1 ms | CLI top-1 ms | MiB top-1 | MiB all | MiB baseline |"
    table = [head, "|" + "---|" * 7, "| cross-door 6.2.2 | 2 | 0.5 | 215.4 | 36 | 36 | 36 |"]
    made = page(table, "m", [])
    assert (
        "| instance | configs | top-1 ms |\n|---|---|---|\n| cross-door 6.2.2 | 2 | 0.5 |" in made
    )
    assert "| instance | CLI top-1 ms | MiB top-1 | MiB all | MiB baseline |" in made
    assert "| cross-door 6.2.2 | 215.4 | 36 | 36 | 36 |" in made
    assert re.search(r"- load average: \d+\.\d\d, ", made)
    old = tmp_path / "old.md"
    old.write_text(made.replace(re.search(r"- load average: .*\n", made).group(0), ""), "utf-8")  # type: ignore[union-attr]
    rewrite(old)
    again = old.read_text("utf-8")
    assert "- load average: not recorded" in again
    assert again.count("| cross-door 6.2.2 |") == 2 and "215.4" in again
    rewrite(old)
    assert old.read_text("utf-8") == again  # a page rewritten is rewritten alike


def test_the_committed_page_fits_and_cites_no_issue() -> None:
    text = (ROOT / "docs" / "explanation" / "benchmarks.md").read_text(encoding="utf-8")
    widths = {line.count("|") - 1 for line in text.splitlines() if line.startswith("|")}
    assert widths and max(widths) <= 8, widths
    assert "- load average:" in text
    assert not re.search(r"[Ii]ssue \d", text)
