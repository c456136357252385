"""A test that needs a system program (tests/programs.py): skipped with the
install command in its reason where the program is missing, failed under CI.
Before, SBCL's tests skipped with "SBCL is not installed" and no way to get it,
valgrind's alike, and Chromium's browser tests failed instead of skipping."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests import programs


def test_a_missing_program_skips_with_how_to_install_it(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("PATH", "/nonexistent")
    monkeypatch.delenv("CI", raising=False)
    monkeypatch.delenv("CFGPLAN_CHROMIUM", raising=False)
    with pytest.raises(pytest.skip.Exception) as skipped:
        programs.program("sbcl")
    assert str(skipped.value) == (
        "sbcl is not installed (sudo apt-get install -y sbcl); .ci/run installs it"
    )
    with pytest.raises(pytest.skip.Exception) as skipped:
        programs.program("chromium", "CFGPLAN_CHROMIUM")
    assert "sudo apt-get install -y chromium, or set CFGPLAN_CHROMIUM=" in str(skipped.value)


def test_under_ci_a_missing_program_fails(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("PATH", "/nonexistent")
    monkeypatch.setenv("CI", "1")
    with pytest.raises(pytest.fail.Exception) as failed:
        programs.program("valgrind")
    assert "sudo apt-get install -y valgrind" in str(failed.value)
    assert "CI must not skip this test" in str(failed.value)


def test_a_program_that_is_there_is_found(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    tool = tmp_path / "sbcl"
    tool.write_text("#!/bin/sh\n", "utf-8")
    tool.chmod(0o755)
    monkeypatch.setenv("PATH", str(tmp_path))
    assert programs.program("sbcl") == str(tool)
    monkeypatch.setenv("CFGPLAN_CHROMIUM", "/opt/chromium")
    assert programs.program("chromium", "CFGPLAN_CHROMIUM") == "/opt/chromium"
