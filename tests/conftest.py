"""The fast loop and the slow set.

``python -m pytest`` runs the fast set: pyproject's ``addopts`` deselects the
tests marked ``slow`` (long property, differential, fuzz, scale and
multi-process tests). ``python -m pytest -m slow`` runs those; ``.ci/run``
runs both. ``-m ""`` runs everything; a slow test named on the command line
runs only with one of these (``-m`` applies to named tests too).

A property test marked ``@pytest.mark.quick(N)`` runs twice: as
``test[quick]`` in the fast set with at most ``N`` examples, and as
``test[full]`` in the slow set exactly as its own ``@settings`` say. The quick
run draws the same derandomized examples' stream, only fewer of them, so it
still catches a broken feature in seconds; the full run is the test as it was.
"""

from __future__ import annotations

from collections.abc import Generator

import pytest
from hypothesis import settings

from tests.programs import program

QUICK = "quick"
"""The marker of a property test that also runs, with fewer examples, in the fast set."""

RUN = "hypothesis_run"
"""The parameter :func:`pytest_generate_tests` adds: ``quick`` or ``full``."""


def _quick_examples(definition: pytest.Function | pytest.Item) -> int | None:
    marker = definition.get_closest_marker(QUICK)
    if marker is None:
        return None
    if len(marker.args) != 1 or not isinstance(marker.args[0], int) or marker.args[0] < 1:
        pytest.fail(
            f"{definition.nodeid}: write @pytest.mark.quick(N), N the fast set's examples (N >= 1)",
            pytrace=False,
        )
    return marker.args[0]


def pytest_generate_tests(metafunc: pytest.Metafunc) -> None:
    """Split a ``quick``-marked property test into its quick and full runs."""
    examples = _quick_examples(metafunc.definition)
    if examples is None:
        return
    test = metafunc.function
    full = getattr(test, "_hypothesis_internal_use_settings", None)
    if not getattr(test, "is_hypothesis_test", False) or not isinstance(full, settings):
        pytest.fail(
            f"{metafunc.definition.nodeid}: @pytest.mark.quick is for @given tests "
            "(or hypothesis keeps its settings elsewhere now: see tests/conftest.py)",
            pytrace=False,
        )
    if examples >= full.max_examples:
        pytest.fail(
            f"{metafunc.definition.nodeid}: quick({examples}) is no fewer than the "
            f"{full.max_examples} examples of the full run: drop the marker",
            pytrace=False,
        )
    metafunc.fixturenames.append(RUN)
    metafunc.parametrize(
        RUN,
        [
            pytest.param(QUICK, id=QUICK),
            pytest.param("full", id="full", marks=pytest.mark.slow),
        ],
    )


@pytest.hookimpl(wrapper=True)
def pytest_runtest_call(item: pytest.Item) -> Generator[None, object, object]:
    """Run the quick run of a ``quick``-marked test with its fewer examples.

    Hypothesis reads a test's settings from the wrapper's
    ``_hypothesis_internal_use_settings`` when the test is called (which is
    also where ``@settings`` puts them); they are swapped for the call only.
    """
    callspec = getattr(item, "callspec", None)
    if callspec is None or callspec.params.get(RUN) != QUICK:
        return (yield)
    examples = _quick_examples(item)
    assert examples is not None and isinstance(item, pytest.Function)
    test = item.obj
    full = test._hypothesis_internal_use_settings
    test._hypothesis_internal_use_settings = settings(full, max_examples=examples)
    try:
        return (yield)
    finally:
        test._hypothesis_internal_use_settings = full


@pytest.fixture
def sbcl() -> str:
    """SBCL's path (a test of the emitted LISP); skipped with the install command
    where it is missing, failed under CI (tests/programs.py)."""
    return program("sbcl")


@pytest.fixture
def chromium() -> str:
    """Chromium's path (``CFGPLAN_CHROMIUM``, else on PATH), as :func:`sbcl`."""
    return program("chromium", "CFGPLAN_CHROMIUM")


@pytest.fixture
def valgrind() -> str:
    """valgrind's path (the instruction counts of benchmarks.instructions), as :func:`sbcl`."""
    return program("valgrind")
