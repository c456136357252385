"""Substitution and matching of flat atoms (cfgplan.planner.unify; 4.5, 2b and 3a)."""

from __future__ import annotations

from cfgplan.planner.unify import bind_name, is_ground, substitute, unify


def test_substitute_replaces_bound_variables_only() -> None:
    assert substitute(("in", "?r", "?room"), {"?r": "Pippi"}) == ("in", "Pippi", "?room")
    assert substitute(("in", "Emil", "Room1"), {"?r": "Pippi"}) == ("in", "Emil", "Room1")


def test_is_ground_looks_at_the_arguments() -> None:
    assert is_ground(("in", "Pippi", "Room1"))
    assert not is_ground(("in", "Pippi", "?room"))


def test_unify_binds_checks_and_keeps_env_when_nothing_is_new() -> None:
    env = {"?r": "Pippi"}
    assert unify(("in", "?r", "?room"), ("in", "Pippi", "Room1"), env) == {
        "?r": "Pippi",
        "?room": "Room1",
    }
    assert env == {"?r": "Pippi"}  # not changed in place
    assert unify(("in", "?r", "?room"), ("in", "Emil", "Room1"), env) is None
    assert unify(("in", "?r", "Room2"), ("in", "Pippi", "Room1"), env) is None
    assert unify(("robot", "?r"), ("robot", "Pippi"), env) is env


def test_unify_a_repeated_variable_needs_equal_values() -> None:
    assert unify(("near", "?a", "?a"), ("near", "X", "X"), {}) == {"?a": "X"}
    assert unify(("near", "?a", "?a"), ("near", "X", "Y"), {}) is None


def test_bind_name_matches_constants_and_repeated_variables() -> None:
    assert bind_name(("?r", "?d"), ("Pippi", "Door1")) == {"?r": "Pippi", "?d": "Door1"}
    assert bind_name(("?r", "Fancy"), ("Pippi", "Plain")) is None
    assert bind_name(("?r", "?r"), ("Pippi", "Emil")) is None
    assert bind_name(("?r", "?r"), ("Pippi", "Pippi")) == {"?r": "Pippi"}
