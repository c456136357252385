"""benchmarks/instructions.py counts one warm planning run's instructions
under callgrind: the count is the planning's (reading and start-up cancel
out), and it repeats, which a time on a shared machine does not."""

from __future__ import annotations

import pytest

from benchmarks.instructions import Options, count

pytestmark = [
    pytest.mark.slow,
    pytest.mark.usefixtures("valgrind"),  # skipped, with how to install it, or failed in CI
]


def test_a_warm_run_counts_alike_twice_and_a_bigger_instance_counts_more() -> None:
    options = Options(runs=1)
    first = count("cross-door 6.2.2", options)
    again = count("cross-door 6.2.2", options)
    assert first > 100_000  # planning, not nothing
    assert abs(first - again) / first < 0.01
    # build-wall's search takes several times cross-door's nodes (18 vs 3).
    assert count("build-wall 6.4", options) > 2 * first
