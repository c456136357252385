"""The documentation site: it builds strictly and offline, its generated reference
pages cover the program, and the code map names every module."""

from __future__ import annotations

import importlib.util
import os
import re
import subprocess
import sys
from pathlib import Path
from types import ModuleType
from typing import Any

import pytest

ROOT = Path(__file__).resolve().parents[2]


def _hook() -> ModuleType:
    """docs/hooks/reference.py, the MkDocs hook that writes the reference pages,
    loaded as MkDocs loads it (its folder on sys.path meanwhile)."""
    path = ROOT / "docs" / "hooks" / "reference.py"
    spec = importlib.util.spec_from_file_location("cfgplan_docs_reference", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    saved = sys.path.copy()
    sys.path.insert(0, str(path.parent))
    try:
        spec.loader.exec_module(module)
    finally:
        sys.path[:] = saved
    return module


def test_code_map_names_every_module() -> None:
    """docs/explanation/code-map.md names every module of cfgplan/ by its path."""
    text = (ROOT / "docs" / "explanation" / "code-map.md").read_text(encoding="utf-8")
    modules = sorted(
        p.relative_to(ROOT).as_posix()
        for p in (ROOT / "cfgplan").rglob("*.py")
        if p.name != "__init__.py" and "__pycache__" not in p.parts
    )
    named = set(re.findall(r"cfgplan/[\w/]+\.py", text))
    missing = [m for m in modules if m not in named]
    assert not missing, f"modules the code map does not name: {missing}"


def test_cli_page_has_every_command_and_option() -> None:
    """reference/cli.md comes from the typer app: every command, every option."""
    import typer

    import cfgplan.cli.commands  # noqa: F401
    from cfgplan.cli.app import app

    page = _hook().cli_page()
    group: Any = typer.main.get_command(app)  # a group (typer may bring its own click)
    ctx = group.context_class(group, info_name="cfgplan")
    for name in group.list_commands(ctx):
        assert f"## cfgplan {name} " in page, name
        command = group.get_command(ctx, name)
        for param in command.params:
            for opt in (*param.opts, *param.secondary_opts):
                shown = opt.upper() if param.param_type_name == "argument" else opt
                assert f"`{shown}" in page or f" {shown}" in page or f"/{shown}" in page, (
                    name,
                    opt,
                )


def test_schema_pages_name_every_model() -> None:
    hook = _hook()
    pages = hook.pages()
    assert set(pages) == set(hook.GENERATED)
    for name in ("PlanDocument", "ConfigurationEntry", "PlanSummary", "SequenceDocument"):
        assert f"### {name} " in pages["reference/json-output.md"]
    for name in ("CallEvent", "SwitchEvent", "InstallEvent", "Staleness"):
        assert f"### {name} " in pages["reference/trace-events.md"]
    for key in ("`world`", "`robots`", "`faults`", "`passage`"):
        assert key in pages["reference/scenario-file.md"]


@pytest.mark.slow  # .ci/run builds the site too
def test_site_builds_strictly_and_offline(tmp_path: Path) -> None:
    """``mkdocs build --strict``: a broken link or anchor, a page missing from
    the nav or a docstring mkdocstrings cannot read fails; the built pages
    load nothing from the network."""
    pytest.importorskip("mkdocs")
    site = tmp_path / "site"
    out = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "-q", "-d", str(site)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=300,
        env={**os.environ, "NO_MKDOCS_2_WARNING": "1"},
    )
    assert out.returncode == 0, out.stderr
    for page in ("reference/cli", "reference/json-output", "reference/trace-events"):
        assert (site / page / "index.html").is_file(), page
    remote = re.compile(r"<(?:link|script|img)[^>]+(?:href|src)=\"(?:https?:)?//", re.I)
    for html in site.rglob("*.html"):
        found = remote.search(html.read_text(encoding="utf-8"))
        assert found is None, f"{html.relative_to(site)} loads {found[0] if found else ''}"
