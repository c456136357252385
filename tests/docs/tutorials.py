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
  as a whole line once trailing spaces are stripped, and the output's other
  non-blank lines must be where a line ``...`` says that lines are left out
  (at the start and end too: a reader is not to take a part for the whole);
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
    """What is wrong with ``stdout`` against the page's ``expected`` lines, or
    ``None``: every expected line occurs as a whole line (trailing spaces
    stripped), in order, and the output's other non-blank lines are where the
    page says ``...`` (at its start and end too), so that a reader never takes
    a part for the whole. An expected block with no line expects nothing."""
    if not expected:
        return None
    lines = [s.rstrip() for s in stdout.splitlines() if s.strip()]
    at = 0
    for want in expected:  # first: a line not printed at all, in order
        if want == LEFT_OUT:
            continue
        try:
            at = lines.index(want, at) + 1
        except ValueError:
            return want
    if _fits(expected, lines):
        return None
    return f"output lines the page leaves out without a {LEFT_OUT!r} line:\n" + "\n".join(
        _unmarked(expected, lines)
    )


def _fits(expected: tuple[str, ...], lines: list[str]) -> bool:
    """Whether ``lines`` are ``expected`` with each ``...`` standing for any
    number of lines (a glob over lines: a run that prints a line one time and
    not the next does not fail where the page marks a gap)."""
    n, m = len(expected), len(lines)
    # can[i][j]: expected[i:] fits lines[j:]
    can = [[False] * (m + 1) for _ in range(n + 1)]
    can[n][m] = True
    for i in range(n - 1, -1, -1):
        for j in range(m, -1, -1):
            if expected[i] == LEFT_OUT:
                can[i][j] = any(can[i + 1][k] for k in range(j, m + 1))
            else:
                can[i][j] = j < m and expected[i] == lines[j] and can[i + 1][j + 1]
    return can[0][0]


def _unmarked(expected: tuple[str, ...], lines: list[str]) -> list[str]:
    """The output's lines that neither an expected line nor a ``...`` accounts
    for, where the in-order match places the expected ones (for the message)."""
    placed: list[int | None] = []
    at = 0
    for want in expected:
        if want == LEFT_OUT:
            placed.append(None)
        else:
            at = lines.index(want, at) + 1
            placed.append(at - 1)
    covered = {w for w in placed if w is not None}
    for k, where in enumerate(placed):
        if where is None:  # a "...": the lines between its neighbours
            before = next((w for w in reversed(placed[:k]) if w is not None), -1)
            after = next((w for w in placed[k + 1 :] if w is not None), len(lines))
            covered.update(range(before + 1, after))
    return [f"  {lines[i]}" for i in range(len(lines)) if i not in covered][:5]
