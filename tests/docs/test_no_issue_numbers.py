"""Docs and code comments say what a thing is, never where it came from: a
reader has no issue tracker ("issue 35" told them nothing)."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
CITED = re.compile(r"\b[Ii]ssues? #?\d+")
SUFFIXES = {".py", ".md", ".lisp", ".toml", ".js", ".css", ".html", ".yml", ".lark"}


def test_no_page_or_comment_cites_an_issue_number() -> None:
    found = []
    for top in ("cfgplan", "docs", "tests", "benchmarks", "examples", "domains", "grammar"):
        for path in sorted((ROOT / top).rglob("*")):
            name = path.relative_to(ROOT).as_posix()
            if path.suffix not in SUFFIXES or "__pycache__" in name:
                continue
            for n, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
                if CITED.search(line) and path != Path(__file__):
                    found.append(f"{name}:{n}: {line.strip()}")
    for name in ("README.md", "mkdocs.yml", "pyproject.toml", ".ci/run"):
        for n, line in enumerate((ROOT / name).read_text(encoding="utf-8").splitlines(), 1):
            if CITED.search(line):
                found.append(f"{name}:{n}: {line.strip()}")
    assert not found, "\n".join(found[:20])
