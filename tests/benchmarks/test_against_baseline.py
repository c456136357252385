"""cfgplan's search against the naive baseline of the benchmarks (issue: search
at scale): on every instance small enough for the baseline, the ranked costs and
configurations agree exactly, labels and order included."""

from __future__ import annotations

from pathlib import Path

import pytest

from benchmarks import families
from benchmarks.naive import distinct, enumerate_all
from cfgplan.configuration.model import Configuration
from cfgplan.planner import plan
from cfgplan.problem import Problem, load

ROOT = Path(__file__).resolve().parents[2]

THESIS = [
    ("cross-door/domain.lisp", "cross-door/state-6.2.2-step1.lisp"),
    ("cross-door/domain-bandwidth.lisp", "cross-door/state-4.6-media.lisp"),
    ("carry-bar/domain.lisp", "carry-bar/state-6.3.2.lisp"),
    ("build-wall/domain.lisp", "build-wall/state-6.4.lisp"),
]
FAMILIES = [
    ("wall", (1, 2, 1)),
    ("wall", (2, 3, 2)),
    ("wall", (2, 4, 3)),
    pytest.param("wall", (3, 4, 2), marks=pytest.mark.slow),
    ("relay", (2, 3, 2)),
    ("relay", (3, 3, 3)),
    # Shared and recursive sub-derivations: one ground method
    # instance under several ancestors, expanded its own way at each.
    ("dag", (3,)),
    ("dag", (5,)),
    ("conversion", (3,)),
    ("conversion", (4,)),
]


def generated(tmp_path: Path, family: str, args: tuple[int, ...]) -> Problem:
    domain, state = getattr(families, family)(*args)
    (tmp_path / "d.lisp").write_text(domain)
    (tmp_path / "s.lisp").write_text(state)
    return load(tmp_path / "d.lisp", tmp_path / "s.lisp")


def unnumbered(configs: list[Configuration]) -> list[Configuration]:
    return [c.model_copy(update={"derivation": 0}) for c in configs]


def agree(problem: Problem) -> None:
    baseline = enumerate_all(problem.task, problem.goal_call)
    derivations, _ = plan(problem.task, problem.goal_call, limit=None, distinct=False)
    assert derivations == baseline  # every derivation, same rank, labels and numbers
    every, _ = plan(problem.task, problem.goal_call, limit=None)
    assert unnumbered(every) == unnumbered(distinct(baseline))
    for k in (1, 10):
        first, _ = plan(problem.task, problem.goal_call, limit=k)
        assert unnumbered(first) == unnumbered(distinct(baseline))[:k]


@pytest.mark.parametrize(("domain", "state"), THESIS)
def test_thesis_domains_agree(domain: str, state: str) -> None:
    agree(load(ROOT / "domains" / domain, ROOT / "domains" / state))


@pytest.mark.parametrize(("family", "args"), FAMILIES)
def test_families_agree(tmp_path: Path, family: str, args: tuple[int, ...]) -> None:
    agree(generated(tmp_path, family, args))


def test_wall_family_counts() -> None:
    """The family's arithmetic (benchmarks/families.py): derivations per pusher are
    L observers x 4 orientation choices (x 2 for a pusher with a laser)."""
    problem = load_wall(2, 3, 2)
    assert len(enumerate_all(problem.task, problem.goal_call)) == 16 * 8  # build-wall's 128


def load_wall(k: int, n: int, lasers: int) -> Problem:
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        return generated(Path(tmp), "wall", (k, n, lasers))
