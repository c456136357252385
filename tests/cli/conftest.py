"""Running the real command line in a subprocess (exit codes, stdout, stderr)."""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]

Run = Callable[..., subprocess.CompletedProcess[str]]


@pytest.fixture
def cfgplan() -> Run:
    """``cfgplan(*args, env=...)`` runs ``python -m cfgplan`` from the repo root."""

    def run(*args: str, env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
        full_env = {**os.environ, **(env or {})}
        return subprocess.run(
            [sys.executable, "-m", "cfgplan", *args],
            cwd=ROOT,
            capture_output=True,
            text=True,
            env=full_env,
            timeout=120,
        )

    return run
