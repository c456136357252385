"""A robot needs cfgplan installed, but ``import cfgplan.runtime`` must stay light:
no planner, IR, pydantic, lark, backends, CLI or Zenoh (its time is measured by
``python -m benchmarks.imports``); nor may ``cfgplan --version`` and the top-level
help load any of it (``python -m benchmarks.startup`` measures them)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from tests.backends.support import ROOT

HEAVY = (
    "pydantic",
    "lark",
    "typer",
    "rich",
    "click",
    "zenoh",
    "cfgplan.ir",
    "cfgplan.planner",
    "cfgplan.backends",
    "cfgplan.syntax",
    "cfgplan.check",
    "cfgplan.configuration",
    "cfgplan.diagnostics",
    "cfgplan.cli",
)


def _modules(code: str) -> list[str]:
    out = subprocess.run(
        [sys.executable, "-c", f"{code}\nimport json, sys\nprint(json.dumps(sorted(sys.modules)))"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert out.returncode == 0, out.stderr
    modules: list[str] = json.loads(out.stdout)
    return modules


def _heavy(modules: list[str]) -> list[str]:
    return [m for m in modules if any(m == h or m.startswith(h + ".") for h in HEAVY)]


def test_importing_the_runtime_brings_nothing_heavy() -> None:
    modules = _modules("import cfgplan.runtime")
    assert "cfgplan.runtime.zenoh_config" in modules  # the Zenoh options, but not zenoh itself
    assert _heavy(modules) == []


def test_an_emitted_robot_program_runs_without_the_planner(tmp_path: object) -> None:
    """What a robot imports to run its program: the runtime, its implementations."""
    code = (
        "from cfgplan.runtime import Registry, load_module\n"
        "from cfgplan.runtime.main import robot_main\n"
        "load_module(__import__('pathlib').Path('examples/cross-door/impl.py'))\n"
    )
    assert _heavy(_modules(code)) == []


def test_the_check_can_fail() -> None:
    assert _heavy(_modules("import cfgplan.backends.part")) != []


FAST = ("cfgplan.cli", "cfgplan.cli.app", "cfgplan.cli.help_text", "cfgplan.cli.registry")
"""What the fast path of the command line loads of :data:`HEAVY`: none of it is heavy
(the registry is a map of names and a decorator: it imports nothing but importlib)."""


def loading(args: list[str], tmp_path: Path) -> tuple[list[str], str]:
    """The modules the command line ``cfgplan ARGS`` has imported when it exits
    (as the console script runs it, whatever it prints), and what it printed."""
    found = tmp_path / "modules.json"
    code = (
        "import atexit, json, pathlib, sys\n"
        f"found = pathlib.Path({str(found)!r})\n"
        "atexit.register(lambda: found.write_text(json.dumps(sorted(sys.modules))))\n"
        "from cfgplan.cli.app import main\n"
        "main()\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code, *args],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=60,
        env={**os.environ, "COLUMNS": "80"},
    )
    assert out.returncode in (0, 2), out.stderr
    modules: list[str] = json.loads(found.read_text("utf-8"))
    return modules, out.stdout


def _loaded_by(args: list[str], tmp_path: Path) -> list[str]:
    """The modules the command line ``cfgplan ARGS`` has imported when it exits."""
    return loading(args, tmp_path)[0]


@pytest.mark.parametrize("args", [["--version"], ["--help"], ["-h"], []])
def test_version_and_help_load_no_library(args: list[str], tmp_path: Path) -> None:
    """``cfgplan --version`` and the top-level help answer at once:
    no typer, click, rich, pydantic or Lark, none of cfgplan's stages."""
    loaded = _loaded_by(args, tmp_path)
    assert "cfgplan.cli.app" in loaded
    assert [m for m in _heavy(loaded) if m not in FAST] == []
    assert "importlib.metadata" not in loaded  # the version is cfgplan.__version__


def test_the_fast_path_check_can_fail(tmp_path: Path) -> None:
    """A command that is not the top-level help loads the typer app."""
    loaded = _loaded_by(["plan", "-h"], tmp_path)
    assert {"typer", "cfgplan.cli.root", "cfgplan.cli.plan"} <= set(loaded)


@pytest.mark.slow
def test_a_json_plan_loads_no_table_library(tmp_path: Path) -> None:
    """rich draws tables: ``plan --format json`` (what a tool reads) does without it,
    nor does planning load the reconfiguration (only ``--fallbacks`` needs it)."""
    args = ["plan", "domains/cross-door/domain.lisp", "domains/cross-door/state-6.2.2-step1.lisp"]
    loaded = _loaded_by([*args, "--format", "json"], tmp_path)
    assert "cfgplan.planner" in loaded
    unwanted = ("rich", "cfgplan.reconfigure")
    assert [m for m in loaded if any(m == u or m.startswith(u + ".") for u in unwanted)] == []
    assert "rich" in _loaded_by(args, tmp_path)  # the table


@pytest.mark.slow
def test_a_plan_printed_as_a_table_loads_what_it_uses_only(tmp_path: Path) -> None:
    """The cheapest configurations of cross-door, as a table: not the
    descriptions of the other formats, nor the solver (clingo: the race forks
    it only past the budget). The strategies it does not run (the parts apart,
    ``--all``'s windows, the dive after a stopped search) live in
    ``cfgplan.planner.combine`` and ``cfgplan.planner.search``, modules merged
    by idea, which a plan loads whole."""
    args = ["plan", "domains/cross-door/domain.lisp", "domains/cross-door/state-6.2.2-step1.lisp"]
    loaded = _loaded_by(args, tmp_path)
    assert "cfgplan.planner.search" in loaded and "rich" in loaded
    unused = ("cfgplan.configuration.describe", "clingo")
    assert [m for m in unused if m in loaded] == []
    assert "cfgplan.configuration.describe" in _loaded_by([*args, "--format", "json"], tmp_path)
