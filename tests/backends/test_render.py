"""Rendering DOT to SVG and PNG without a system Graphviz (pygraphviz's bundled
engine), or with a ``dot`` program on PATH (:mod:`cfgplan.backends.render`);
the ``cfgplan render`` command is tested in ``tests/cli/test_render.py``."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from typer.testing import CliRunner

import cfgplan.cli.render  # noqa: F401  (loads the command module)
from cfgplan.backends import render as engine
from cfgplan.backends.render import render
from cfgplan.cli.app import app
from cfgplan.diagnostics import CfgplanError

ROOT = Path(__file__).resolve().parents[2]
CROSS = ("domains/cross-door/domain.lisp", "domains/cross-door/state-6.2.2-step1.lisp")
SVG = "{http://www.w3.org/2000/svg}"
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
SMALL = 'digraph g { a -> b [label="x"] }'


def invoke(*args: str) -> tuple[int, str]:
    result = CliRunner().invoke(app, ["render", *args])
    return result.exit_code, result.output


def svg_texts(data: bytes) -> list[str]:
    """Every piece of text an SVG shows."""
    root = ET.fromstring(data)
    assert root.tag == f"{SVG}svg"
    return [t.text or "" for t in root.iter(f"{SVG}text")]


def test_engine_is_available() -> None:
    """pygraphviz (a dependency) brings Graphviz along: no system dot needed."""
    assert engine.engine() is not None


def test_render_svg_and_png() -> None:
    texts = svg_texts(render(SMALL, "svg"))
    assert {"a", "b", "x"} <= set(texts)
    png = render(SMALL, "png")
    assert png.startswith(PNG_MAGIC) and len(png) > 500


def test_render_rejects_other_formats() -> None:
    with pytest.raises(CfgplanError, match="cannot render"):
        render(SMALL, "pdf")  # type: ignore[arg-type]


def test_bad_dot_is_an_input_error() -> None:
    with pytest.raises(CfgplanError, match="could not render"):
        render("digraph { a -> }", "svg")


def test_missing_engine_is_a_clear_error(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(engine, "load_pygraphviz", lambda: None)
    monkeypatch.setattr(engine, "system_dot", lambda: None)
    with pytest.raises(CfgplanError) as info:
        render(SMALL, "svg")
    (diagnostic,) = info.value.diagnostics
    assert "no Graphviz layout engine" in diagnostic.message
    assert diagnostic.hint is not None and "pygraphviz" in diagnostic.hint


def test_falls_back_to_a_dot_program(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    """Without pygraphviz (no wheel for the platform), a dot on PATH is used."""
    fake = tmp_path / "dot"
    fake.write_text('#!/bin/sh\ncat >/dev/null\necho "<svg $1/>"\necho "dot: note" >&2\n')
    fake.chmod(0o755)
    monkeypatch.setattr(engine, "load_pygraphviz", lambda: None)
    monkeypatch.setattr(engine, "system_dot", lambda: str(fake))
    assert engine.engine() == str(fake)
    assert render(SMALL, "svg") == b"<svg -Tsvg/>\n"
    fake.write_text("#!/bin/sh\nexit 3\n")
    with pytest.raises(CfgplanError, match="failed with exit code 3"):
        render(SMALL, "png")


def test_fontconfig_noise_is_dropped(capsys: pytest.CaptureFixture[str]) -> None:
    engine._forward(
        'Fontconfig warning: "/etc/fonts/x.conf", line 6: unknown element "reset-dirs"\n'
        "Warning: something Graphviz says\n"
    )
    assert capsys.readouterr().err == "Warning: something Graphviz says\n"
