"""The fast loop and the slow set (tests/conftest.py): a property test
marked ``quick(N)`` runs with ``N`` examples in the fast set and with all of its
own in the slow set; ``slow`` tests are left out of ``python -m pytest``."""

from __future__ import annotations

import tomllib
from collections import Counter
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

pytest_plugins = ["pytester"]

PROPERTY = """
import os
from pathlib import Path

import pytest
from hypothesis import given, settings, strategies as st

LOG = Path(__file__).with_name("calls.log")


def _called() -> None:
    with LOG.open("a") as log:
        log.write(os.environ["PYTEST_CURRENT_TEST"].split(" ")[0] + "\\n")


@pytest.mark.quick(3)
@settings(max_examples=40, derandomize=True, database=None)
@given(st.integers())
def test_property(n: int) -> None:
    _called()


@pytest.mark.slow
def test_long() -> None:
    _called()


def test_short() -> None:
    _called()
"""


@pytest.fixture
def project(pytester: pytest.Pytester) -> pytest.Pytester:
    """A project with this suite's conftest and pytest settings (addopts, markers)."""
    pytester.makeconftest((ROOT / "tests" / "conftest.py").read_text(encoding="utf-8"))
    options = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    pytest_options = options["tool"]["pytest"]["ini_options"]
    lines = "\n    ".join(pytest_options["markers"])
    pytester.makeini(f"[pytest]\naddopts = {pytest_options['addopts']}\nmarkers =\n    {lines}\n")
    return pytester


def _calls(pytester: pytest.Pytester, *args: str) -> Counter[str]:
    pytester.makepyfile(test_it=PROPERTY)
    log = pytester.path / "calls.log"
    log.unlink(missing_ok=True)
    result = pytester.runpytest_inprocess("-p", "no:cacheprovider", *args)
    assert result.ret == 0, result.stdout.str()
    return Counter(log.read_text().split()) if log.exists() else Counter()


def test_the_fast_set_runs_the_quick_run_and_leaves_the_slow_out(project: pytest.Pytester) -> None:
    assert _calls(project) == {
        "test_it.py::test_property[quick]": 3,
        "test_it.py::test_short": 1,
    }


def test_the_slow_set_runs_the_full_run_and_the_slow_tests(project: pytest.Pytester) -> None:
    assert _calls(project, "-m", "slow") == {
        "test_it.py::test_property[full]": 40,
        "test_it.py::test_long": 1,
    }


MISUSED = {
    "test_plain.py": (
        "@pytest.mark.quick(3)\ndef test_plain() -> None: ...",
        "is for @given tests",
    ),
    "test_no_fewer.py": (
        "@pytest.mark.quick(50)\n@settings(max_examples=40)\n@given(st.integers())\n"
        "def test_p(n: int) -> None: ...",
        "no fewer than the 40 examples",
    ),
    "test_no_count.py": (
        "@pytest.mark.quick()\n@given(st.integers())\ndef test_p(n: int) -> None: ...",
        "N >= 1",
    ),
}


def test_a_misused_quick_marker_is_refused(project: pytest.Pytester) -> None:
    header = "import pytest\nfrom hypothesis import given, settings, strategies as st\n\n"
    for name, (test, _) in MISUSED.items():
        (project.path / name).write_text(header + test + "\n")
    result = project.runpytest_inprocess("-p", "no:cacheprovider")
    assert result.ret != 0
    out = result.stdout.str() + result.stderr.str()
    for name, (_, says) in MISUSED.items():
        assert f"{name}::" in out and says in out, (name, out)
