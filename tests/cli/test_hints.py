"""Hints a newcomer's slips got none of (a review's first hour): a robot's
name in the wrong case, a misspelt bundled scenario, the domain and the state
given the other way round."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.cli.conftest import Run

CROSS = ["domains/cross-door/domain.lisp", "domains/cross-door/state-6.2.2-step1.lisp"]
IMPL = ["--impl", "examples/cross-door/impl.py"]


@pytest.mark.parametrize(
    ("args", "said", "hint"),
    [
        (
            ["run", *CROSS, *IMPL, "--robot", "pippi"],
            "no robot pippi in this configuration (its robots: Pippi, Emil)",
            "symbols are case-sensitive: did you mean Pippi?",
        ),
        (
            ["launch", *CROSS, *IMPL, "--robot", "pippi"],
            "no robot pippi in domains/cross-door/state-6.2.2-step1.lisp",
            "symbols are case-sensitive: did you mean Pippi?",
        ),
        (
            ["simulate", "cross-dor", "--out", "never"],
            "cross-dor: no such scenario file, nor a bundled scenario",
            "did you mean cross-door?",
        ),
        (
            ["plan", CROSS[1], CROSS[0]],
            "a domain file holds only make-functionality and make-config-method forms",
            "the domain file comes first, then the state file (DOMAIN STATE)",
        ),
    ],
    ids=["run", "launch", "simulate", "swapped"],
)
def test_a_slip_gets_a_hint(cfgplan: Run, args: list[str], said: str, hint: str) -> None:
    out = cfgplan(*args)
    assert out.returncode == 1, out.stderr
    assert said in out.stderr and f"hint: {hint}" in out.stderr
    assert "Traceback" not in out.stderr


def test_a_state_form_in_a_domain_with_its_own_forms_is_no_swap(
    cfgplan: Run, tmp_path: Path
) -> None:
    domain = tmp_path / "d.lisp"
    domain.write_text(
        "(make-functionality :name '(camera ?r) :out '((image ?r)))\n(state (robot A))\n",
        encoding="utf-8",
    )
    out = cfgplan("plan", str(domain), CROSS[1])
    assert out.returncode == 1
    assert "hint: put (state ...) and (goal ...) in the state file" in out.stderr
