"""A robot needs cfgplan installed, but ``import cfgplan.runtime`` must stay light:
no planner, IR, pydantic, lark, backends, CLI or Zenoh (its time is measured by
``python -m benchmarks.imports``)."""

from __future__ import annotations

import json
import subprocess
import sys

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
    assert "cfgplan.runtime.zenoh_transport" in modules  # imported, but not zenoh itself
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
