"""The fast path of ``cfgplan --version`` and the top-level help:
answered without typer, from a text pre-rendered from the typer app, which
must stay what typer prints (what each loads: tests/runtime/test_imports.py)."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from cfgplan import __version__
from cfgplan.cli import help_text
from cfgplan.cli.root import HELP_WIDTH, render_help
from tests.cli.conftest import ROOT, Run

TYPER = (
    "import sys\nfrom cfgplan.cli.app import _run, register\n"
    "register(sys.argv[1:])\nsys.exit(_run())"
)
"""The slow path: the typer app answers the command line, whatever it is."""


def _typer(args: list[str], columns: str) -> tuple[int, str, str]:
    """What typer itself prints for ``args`` on a terminal ``columns`` wide."""
    env = {**os.environ, "COLUMNS": columns}
    out = subprocess.run(
        [sys.executable, "-c", TYPER, *args],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )
    return out.returncode, out.stdout, out.stderr


def test_the_help_text_is_typers_rendering() -> None:
    """Fails when a command, an option or a summary changes without the text
    being generated again: ``python -m cfgplan.cli.root``."""
    assert help_text.WIDTH == HELP_WIDTH
    assert render_help(HELP_WIDTH) == help_text.HELP


def test_the_help_lists_the_commands_whatever_was_imported_first() -> None:
    """The commands register on the app as their modules are imported; the
    help lists them by name all the same (in CI, a test that imported
    ``cfgplan.cli.render`` first put ``render`` at the top of typer's help and
    the pre-rendered text no longer matched)."""
    code = (
        "import cfgplan.cli.run, cfgplan.cli.render\n"
        "from cfgplan.cli import help_text\n"
        "from cfgplan.cli.root import render_help\n"
        "assert render_help() == help_text.HELP, render_help()\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, timeout=60
    )
    assert out.returncode == 0, out.stderr


@pytest.mark.slow
@pytest.mark.parametrize(
    ("args", "status", "stream"), [(["--help"], 0, 1), (["-h"], 0, 1), ([], 2, 2)]
)
def test_the_fast_help_is_what_typer_prints(
    cfgplan: Run, args: list[str], status: int, stream: int
) -> None:
    for columns in ("80", "200"):  # click renders at most 80 columns wide
        out = cfgplan(*args, env={"COLUMNS": columns})
        assert (out.returncode, out.stdout, out.stderr) == _typer(args, columns)
        assert out.returncode == status
        assert (out.stdout, out.stderr)[stream - 1] == help_text.HELP


def test_a_narrow_terminal_gets_typers_own_help(cfgplan: Run) -> None:
    """The pre-rendered text is 80 columns wide: on a narrower terminal typer
    renders the help (the text differs, so this is not the fast path)."""
    out = cfgplan("--help", env={"COLUMNS": "60"})
    assert out.returncode == 0
    assert out.stdout == render_help(60) != help_text.HELP


@pytest.mark.slow
def test_the_fast_version_is_typers(cfgplan: Run) -> None:
    out = cfgplan("--version")
    assert (out.returncode, out.stdout, out.stderr) == (0, f"cfgplan {__version__}\n", "")
    assert _typer(["--version"], "80") == (out.returncode, out.stdout, out.stderr)
    assert cfgplan("--version", "--help").stdout == out.stdout  # typer answers that one


def _gc_after(code: str) -> list[object]:
    out = subprocess.run(
        [sys.executable, "-c", f"import gc, json\nfrom cfgplan.cli import app\n{code}"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert out.returncode == 0, out.stderr
    found: list[object] = json.loads(out.stdout)
    return found


@pytest.mark.slow
def test_what_a_command_loads_is_frozen_once() -> None:
    """The modules a command loads are frozen out of the garbage collector's
    work (:func:`cfgplan.cli.app._load`), once a process; the collector is left
    as it was found, on or off."""
    on, frozen = _gc_after(
        "app._load(['plan'])\nprint(json.dumps([gc.isenabled(), gc.get_freeze_count()]))"
    )
    assert on is True and isinstance(frozen, int) and frozen > 10_000
    again = _gc_after(
        "app._load(['plan'])\nfirst = gc.get_freeze_count()\nx = [[] for _ in range(1000)]\n"
        "app._load(['check'])\nprint(json.dumps([first, gc.get_freeze_count()]))"
    )
    # The second command line froze nothing more: freezing again would add the
    # 1,000 lists at least. A frozen object may die (a command module's
    # annotations, evaluated as it loads, go through typing's bounded caches).
    assert again[1] <= again[0]
    off = _gc_after("gc.disable()\napp._load(['plan'])\nprint(json.dumps([gc.isenabled()]))")
    assert off == [False]


@pytest.mark.slow
def test_what_one_command_reads_is_frozen_and_many_commands_freeze_nothing() -> None:
    """The console script (one command, then exit: ``app.ONE_COMMAND``)
    freezes the problem it read (:func:`cfgplan.cli.options.load_problem`),
    so that the search's collections do not walk it; a process running
    several commands (a test, a program embedding the app) freezes nothing
    there, as frozen objects are never collected."""
    read = (
        "from cfgplan.cli.options import load_problem\n"
        "from pathlib import Path\n"
        "app._load(['plan'])\n"
        "d = Path('domains/cross-door')\n"
        "before = gc.get_freeze_count()\n"
        "{set}load_problem(d / 'domain.lisp', d / 'state-6.2.2-step1.lisp', None, None)\n"
        "print(json.dumps([before, gc.get_freeze_count()]))"
    )
    one = _gc_after(read.format(set="app.ONE_COMMAND.set(True)\n"))
    many = _gc_after(read.format(set=""))
    assert isinstance(one[0], int) and isinstance(one[1], int)
    assert isinstance(many[0], int) and isinstance(many[1], int)
    assert one[1] - one[0] > 1_000  # the IR, the task, the parser's work
    assert abs(many[1] - many[0]) < 100  # (frozen objects die, a few move)


@pytest.mark.slow
def test_a_command_that_plans_and_exits_collects_young_objects_less_often() -> None:
    """After reading, a one-command process that plans and exits makes the
    cycle collector's young collections rarer (:data:`cfgplan.cli.options.YOUNG`
    new objects apart): the search makes many lasting objects and next to
    no cyclic garbage. A command that runs on (``lasting``: a society) and a
    process running several commands keep Python's pace; the collector stays
    on and still collects a cycle."""
    read = (
        "from cfgplan.cli.options import YOUNG, load_problem\n"
        "from pathlib import Path\n"
        "app._load(['plan'])\n"
        "d = Path('domains/cross-door')\n"
        "before = gc.get_threshold()[0]\n"
        "{set}load_problem(d / 'domain.lisp', d / 'state-6.2.2-step1.lisp', None, None{lasting})\n"
        "a = []; a.append(a); del a\n"
        "print(json.dumps([before, gc.get_threshold()[0], YOUNG, gc.isenabled(), gc.collect()]))"
    )
    one = _gc_after(read.format(set="app.ONE_COMMAND.set(True)\n", lasting=""))
    lasting = _gc_after(read.format(set="app.ONE_COMMAND.set(True)\n", lasting=", lasting=True"))
    many = _gc_after(read.format(set="", lasting=""))
    assert one[0] == 700 and one[1] == one[2] and one[2] != 700  # Python's default, then YOUNG
    assert lasting[1] == lasting[0] == many[1] == many[0] == 700
    for found in (one, lasting, many):
        assert found[3] is True and isinstance(found[4], int) and found[4] >= 1  # the cycle
