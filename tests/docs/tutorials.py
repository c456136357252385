"""Executable tutorials: the code blocks of ``docs/tutorials/*.md`` and how they are run.

The convention (docs/development.md):

* every fenced block whose info string is exactly ``sh`` is run, in document
  order, with ``bash -euo pipefail``, in one scratch directory per page (the
  blocks of a page share it) that holds copies of the repository's
  ``domains/`` and ``examples/``, with the installed ``cfgplan`` on PATH; each
  block has :data:`LIMIT` seconds, and its process group is killed afterwards;
* a fenced block whose info string is exactly ``text`` directly after a ``sh``
  block (nothing but blank lines between) is its expected output: every
  non-blank line of it must occur in the block's stdout, in that order, each
  as a whole line once trailing spaces are stripped; a line ``...`` says that
  lines are left out there (a reader is not to take a part for the whole),
  and is itself not looked for;
* blocks with any other info string are shown, not run.
"""

from __future__ import annotations

import contextlib
import os
import re
import shutil
import signal
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
TUTORIALS = ROOT / "docs" / "tutorials"
LIMIT = 120.0
"""Seconds one block may take."""

LEFT_OUT = "..."
"""An expected output's line for lines of the output the page leaves out."""

_FENCE = re.compile(r"^(?P<indent> *)(?P<fence>`{3,}|~{3,})(?P<info>.*)$")


@dataclass(frozen=True)
class Block:
    """A fenced code block: its info string, text, and first line (1-based)."""

    info: str
    text: str
    line: int
    follows: Block | None = None  # the block just before it, with only blank lines between


@dataclass(frozen=True)
class Step:
    """A ``sh`` block and the lines it must print (from the ``text`` block after it)."""

    script: str
    line: int
    expected: tuple[str, ...]


def blocks(markdown: str) -> list[Block]:
    """Every fenced block of ``markdown``, in order (CommonMark fences: the
    closing fence uses the same character, at least as many, nothing after)."""
    found: list[Block] = []
    lines = markdown.splitlines()
    i, last_end = 0, -1
    while i < len(lines):
        opening = _FENCE.match(lines[i])
        if opening is None or (opening["fence"][0] == "`" and "`" in opening["info"]):
            i += 1
            continue
        indent, fence = len(opening["indent"]), opening["fence"]
        body: list[str] = []
        j = i + 1
        while j < len(lines):
            closing = _FENCE.match(lines[j])
            if (
                closing is not None
                and closing["fence"][0] == fence[0]
                and len(closing["fence"]) >= len(fence)
                and not closing["info"].strip()
            ):
                break
            line = lines[j]
            body.append(line[min(indent, len(line) - len(line.lstrip(" "))) :])
            j += 1
        between = lines[last_end + 1 : i] if found else ["x"]
        previous = found[-1] if found and all(not s.strip() for s in between) else None
        found.append(Block(opening["info"].strip(), "\n".join(body) + "\n", i + 1, previous))
        i, last_end = j + 1, j
    return found


def steps(markdown: str) -> list[Step]:
    """The ``sh`` blocks of a page with their expected lines."""
    found = blocks(markdown)
    out: list[Step] = []
    for k, block in enumerate(found):
        if block.info != "sh":
            continue
        expected: tuple[str, ...] = ()
        after = found[k + 1] if k + 1 < len(found) else None
        if after is not None and after.info == "text" and after.follows is block:
            expected = tuple(s.rstrip() for s in after.text.splitlines() if s.strip())
        out.append(Step(block.text, block.line, expected))
    return out


def scratch(folder: Path) -> Path:
    """A scratch directory holding copies of ``domains/`` and ``examples/``."""
    for name in ("domains", "examples"):
        shutil.copytree(ROOT / name, folder / name, ignore=shutil.ignore_patterns("__pycache__"))
    return folder


def environment() -> dict[str, str]:
    """This environment, with the installed ``cfgplan`` (beside this Python) first on PATH."""
    here = str(Path(sys.executable).parent)
    env = {**os.environ, "PATH": here + os.pathsep + os.environ.get("PATH", "")}
    for name in ("COLUMNS", "LINES"):  # as wide as when piped, whatever terminal runs the tests
        env.pop(name, None)
    return env


def run(step: Step, folder: Path, limit: float = LIMIT) -> subprocess.CompletedProcess[str]:
    """Run one block in ``folder`` with ``bash -euo pipefail``, then kill
    what is left of its process group (a background process that outlived it)."""
    process = subprocess.Popen(
        ["bash", "-euo", "pipefail", "-c", step.script],
        cwd=folder,
        env=environment(),
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )
    try:
        stdout, stderr = process.communicate(timeout=limit)
    except subprocess.TimeoutExpired:
        _kill(process.pid)
        stdout, stderr = process.communicate(timeout=10)
        stderr += f"\n[timed out after {limit:g} s and killed]"
        return subprocess.CompletedProcess(process.args, -9, stdout, stderr)
    _kill(process.pid)
    return subprocess.CompletedProcess(process.args, process.returncode, stdout, stderr)


def _kill(group: int) -> None:
    with contextlib.suppress(ProcessLookupError, PermissionError):
        os.killpg(group, signal.SIGKILL)


def missing(expected: tuple[str, ...], stdout: str) -> str | None:
    """The first expected line not found in ``stdout`` (as a whole line, in
    order after the previous one), or ``None`` when every one is there."""
    lines = [s.rstrip() for s in stdout.splitlines()]
    at = 0
    for want in expected:
        if want == LEFT_OUT:
            continue
        try:
            at = lines.index(want, at) + 1
        except ValueError:
            return want
    return None
