"""Lay out DOT source and render it to SVG or PNG, with no system Graphviz needed.

The engine is pygraphviz (a dependency of cfgplan): since 2.0 its wheels for
Linux (x86_64, aarch64; glibc 2.28+), macOS arm64 and Windows x86_64 bundle
Graphviz itself (libgvc with the dot layout, core (SVG) and cairo (PNG)
plugins), so ``pip install cfgplan`` is enough. Where pygraphviz is not
installed, a program on PATH with dot's command line is used instead: Graphviz's
``dot``, or ``graphviz-pure`` (a Rust port of Graphviz on PyPI, with wheels for
more platforms); with none, :func:`render` raises a :class:`CfgplanError`
saying what to install.

The bundled fontconfig is older than some systems' (Debian 12) and warns about
their configuration on every run; those warnings are dropped, anything else
Graphviz says is passed on to stderr.
"""

from __future__ import annotations

import contextlib
import importlib
import os
import shutil
import subprocess
import sys
import tempfile
from collections.abc import Iterator
from typing import Any, Literal

from cfgplan.diagnostics import error

Format = Literal["svg", "png"]
FORMATS: tuple[Format, ...] = ("svg", "png")
PROGRAMS = ("dot", "graphviz-pure")
"""Programs with dot's command line (``-Tsvg``), tried in this order."""
INSTALL_HINT = (
    "pip install 'pygraphviz>=2.0.4' (its wheels bundle Graphviz) or graphviz-pure, "
    "or install Graphviz so that its dot program is on PATH"
)
_NOISE = "Fontconfig warning:"


def load_pygraphviz() -> Any | None:
    """The pygraphviz module, or None when it is not installed or cannot load."""
    try:
        return importlib.import_module("pygraphviz")
    except ImportError:
        return None


def system_dot() -> str | None:
    """The path of the first of :data:`PROGRAMS` found on PATH, if any."""
    for name in PROGRAMS:
        path = shutil.which(name)
        if path is not None:
            return path
    return None


def engine() -> str | None:
    """Which engine :func:`render` would use: ``pygraphviz 2.0.4``, ``/usr/bin/dot`` or None."""
    module = load_pygraphviz()
    if module is not None:
        return f"pygraphviz {module.__version__}"
    return system_dot()


def render(dot_source: str, fmt: Format) -> bytes:
    """Lay out ``dot_source`` with dot and return the SVG or PNG bytes."""
    if fmt not in FORMATS:
        raise error(f"cannot render to {fmt!r}: expected one of {', '.join(FORMATS)}")
    module = load_pygraphviz()
    if module is not None:
        return _with_pygraphviz(module, dot_source, fmt)
    dot = system_dot()
    if dot is not None:
        return _with_program(dot, dot_source, fmt)
    raise error(
        f"cannot render {fmt.upper()}: no Graphviz layout engine is installed",
        hint=INSTALL_HINT + "; or write .dot and lay it out elsewhere",
    )


def _with_pygraphviz(module: Any, dot_source: str, fmt: Format) -> bytes:
    with _graphviz_stderr():
        try:
            graph = module.AGraph(string=dot_source)
            data = graph.draw(format=fmt, prog="dot")
        except Exception as exc:  # pygraphviz raises ValueError, DotError, ...
            raise error(f"Graphviz (pygraphviz) could not render {fmt.upper()}: {exc}") from None
    if not isinstance(data, bytes) or not data:
        raise error(f"Graphviz (pygraphviz) produced no {fmt.upper()} output")
    return data


def _with_program(dot: str, dot_source: str, fmt: Format) -> bytes:
    try:
        done = subprocess.run(
            [dot, f"-T{fmt}"], input=dot_source.encode("utf-8"), capture_output=True, check=False
        )
    except OSError as exc:
        raise error(f"cannot run {dot}: {exc.strerror}", hint=INSTALL_HINT) from None
    _forward(done.stderr.decode("utf-8", "replace"))
    if done.returncode != 0 or not done.stdout:
        raise error(f"{dot} -T{fmt} failed with exit code {done.returncode}")
    return done.stdout


@contextlib.contextmanager
def _graphviz_stderr() -> Iterator[None]:
    """Collect what the C library writes on file descriptor 2, then pass it on
    without the fontconfig noise."""
    sys.stderr.flush()
    try:
        saved = os.dup(2)
    except OSError:  # no usable descriptor 2: nothing to filter
        yield
        return
    with tempfile.TemporaryFile() as captured:
        os.dup2(captured.fileno(), 2)
        try:
            yield
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            captured.seek(0)
            _forward(captured.read().decode("utf-8", "replace"))


def _forward(text: str) -> None:
    lines = [line for line in text.splitlines() if line and not line.startswith(_NOISE)]
    if lines:
        print("\n".join(lines), file=sys.stderr)
