"""System programs some tests need (Chromium, SBCL, valgrind), as `.ci/run`
installs them and the README's development section names them.

A test that needs one asks for the fixture of its name (``sbcl``, ``chromium``,
``valgrind``: tests/conftest.py) or calls :func:`program`: where the
program is missing the test is skipped, and the reason says how to install it;
under CI (the environment variable ``CI`` set, as ``.ci/run`` and every CI
service set it) a missing program is a failure instead, so that CI never
passes by skipping what it was meant to run.
"""

from __future__ import annotations

import os
import shutil

import pytest

PACKAGES = {"chromium": "chromium", "sbcl": "sbcl", "valgrind": "valgrind"}
"""The Debian package of each program (``apt-get install -y NAME``)."""


def path_of(name: str, variable: str | None = None) -> str | None:
    """Where program ``name`` is: ``$variable`` if set (``CFGPLAN_CHROMIUM``), else on PATH."""
    given = os.environ.get(variable) if variable else None
    return given or shutil.which(name)


def program(name: str, variable: str | None = None) -> str:
    """The path of program ``name``; skip the test (fail it under CI) when it is missing."""
    found = path_of(name, variable)
    if found is not None:
        return found
    how = f"sudo apt-get install -y {PACKAGES.get(name, name)}"
    if variable:
        how += f", or set {variable}=/path/to/{name}"
    reason = f"{name} is not installed ({how}); .ci/run installs it"
    if os.environ.get("CI"):
        pytest.fail(f"{reason}, and CI must not skip this test", pytrace=False)
    pytest.skip(reason)
