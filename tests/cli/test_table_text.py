"""The tables ``plan`` prints (configurations, sequences, fallbacks) are rich
tables rendered as plain text by :func:`cfgplan.cli.formats.plain`: what the
input names is printed as written, never read as rich markup or emoji codes
(a symbol may hold ``[``, ``]`` and ``:``), and rich's emoji table is not
loaded for it (start-up)."""

from __future__ import annotations

import subprocess
import sys

from rich.table import Table

from cfgplan.cli.formats import plain
from tests.cli.conftest import ROOT


def _table(*cells: str) -> Table:
    shown = Table(title=cells[0])
    shown.add_column("name")
    for cell in cells[1:]:
        shown.add_row(cell)
    return shown


def test_names_print_as_written() -> None:
    """Markup (``[bold]``, ``[/]``) and emoji codes (``:smile:``) in a title
    or a cell come out unchanged."""
    text = plain(_table("[red]go(:smile:)", "[bold]Pippi[/] and Emil", "x:smile:"), 60)
    assert "[red]go(:smile:)" in text
    assert "[bold]Pippi[/] and Emil" in text
    assert "x:smile:" in text
    assert "\x1b" not in text  # no colour, no style


def test_a_table_is_as_wide_as_asked() -> None:
    """The widest line is at most ``width`` columns; a long cell wraps."""
    text = plain(_table("t", "word " * 30), 40)
    assert max(len(line) for line in text.splitlines()) <= 40
    assert text.count("word") == 30


def test_a_table_loads_no_emoji_table() -> None:
    """Rendering a table, in a fresh process, does not import rich's emoji codes."""
    code = (
        "import sys\n"
        "from rich.table import Table\n"
        "from cfgplan.cli.formats import plain\n"
        "t = Table(title='Configurations for go(Pippi)')\n"
        "t.add_column('robots')\n"
        "t.add_row('Pippi, Emil')\n"
        "assert 'Pippi, Emil' in plain(t, 80)\n"
        "print('rich._emoji_codes' in sys.modules)\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=60
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "False"
