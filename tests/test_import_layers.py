"""The package's layers, read from the source (every import, those inside
functions too): a lower module never imports the one built on it, so that
there is no import cycle for the next reader to untangle."""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "cfgplan"


def _name(path: Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imports() -> dict[str, set[str]]:
    """Each module of cfgplan and the cfgplan modules it imports, anywhere in it."""
    found: dict[str, set[str]] = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        module = _name(path)
        names: set[str] = set()
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Import):
                names.update(a.name for a in node.names)
            elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
                names.add(node.module)
                names.update(f"{node.module}.{a.name}" for a in node.names)
        found[module] = {n for n in names if n.startswith("cfgplan")}
    return found


def _reaches(graph: dict[str, set[str]], module: str, target: str) -> bool:
    return any(n == target or n.startswith(target + ".") for n in graph.get(module, set()))


def test_the_robot_knows_nothing_of_installing() -> None:
    """runtime/install builds on runtime/executor (it writes the robot's wiring);
    the executor imported install back (for build)."""
    graph = imports()
    assert _reaches(graph, "cfgplan.runtime.install", "cfgplan.runtime.executor")
    assert not _reaches(graph, "cfgplan.runtime.executor", "cfgplan.runtime.install")


def test_the_security_package_does_not_import_the_runtime() -> None:
    """The runtime uses the security package (identity, rate limits, TLS); the
    security package took RunError and the key chunks from the runtime: a cycle
    of packages. Both now come from modules below them."""
    graph = imports()
    security = [m for m in graph if m.startswith("cfgplan.security")]
    assert security
    wrong = {m: sorted(graph[m]) for m in security if _reaches(graph, m, "cfgplan.runtime")}
    assert not wrong
    assert any(
        _reaches(graph, m, "cfgplan.security") for m in graph if m.startswith("cfgplan.runtime")
    )


def test_the_command_line_has_one_map_of_commands_and_no_cycle() -> None:
    """The commands are one map, name -> module:function (cli/registry.py),
    which imports nothing of the command line; the root group loads a command
    from it when asked (click's lazy subcommands). Before, app -> root ->
    commands -> app: each command module registered itself on the app."""
    graph = imports()
    cli = [m for m in graph if m.startswith("cfgplan.cli.")]
    assert not [m for m in graph["cfgplan.cli.registry"] if m.startswith("cfgplan.cli")]
    assert not _reaches(graph, "cfgplan.cli.root", "cfgplan.cli.app")
    assert not _reaches(graph, "cfgplan.cli.commands", "cfgplan.cli.app")
    registering = [  # the entry point runs the app; no other module takes it
        m
        for m in cli
        if m != "cfgplan.cli.app"
        and ("cfgplan.cli.app.app" in graph[m] or "cfgplan.cli.root.app" in graph[m])
    ]
    assert not registering  # no module takes the app to add itself to it
    from cfgplan.cli.registry import COMMANDS, SETTINGS, load

    for name in COMMANDS:
        target = load(name)
        assert hasattr(target, SETTINGS) or name == "keys", name
