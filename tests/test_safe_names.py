"""Safe file names for names from the input (cfgplan/safe_names.py)."""

from __future__ import annotations

import re

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cfgplan.safe_names import MAX_STEM, file_stems, safe_stem

STEM = re.compile(r"[a-z0-9_][a-z0-9_-]*")


def test_plain_names_keep_their_name_in_lower_case() -> None:
    assert file_stems(["Emil", "Pippi", "Rasmus", "robot-2", "R_1"]) == {
        "Emil": "emil",
        "Pippi": "pippi",
        "Rasmus": "rasmus",
        "robot-2": "robot-2",
        "R_1": "r_1",
    }


@pytest.mark.parametrize(
    ("name", "kept"),
    [
        ("../../escaped", "escaped"),
        ("/etc/passwd", "etc_passwd"),
        ("a\\b", "a_b"),
        ("a\x00b", "a_b"),
        ("..", "name"),
        (".", "name"),
        ("-rf", "rf"),
        ("CON", "con"),
        ("nul", "nul"),
        ("LPT9", "lpt9"),
        ("Ünïcödé", "n_c_d"),
        ("🤖", "name"),
    ],
)
def test_unsafe_names_keep_their_safe_part_and_get_a_digest(name: str, kept: str) -> None:
    stem = safe_stem(name)
    assert re.fullmatch(re.escape(kept) + r"-[0-9a-f]{8}", stem), stem
    assert safe_stem(name) == stem  # the same on every run


def test_a_very_long_name_is_cut() -> None:
    stem = safe_stem("x" * 10_000)
    assert stem == "x" * MAX_STEM + "-" + stem[-8:]
    assert safe_stem("x" * MAX_STEM) == "x" * MAX_STEM


def test_case_only_differences_and_reserved_stems_get_distinct_names() -> None:
    stems = file_stems(["Emil", "EMIL", "emil", "run_all", "Pippi"], reserved=["run_all"])
    assert stems["Pippi"] == "pippi"
    clashing = [stems[n] for n in ("Emil", "EMIL", "emil", "run_all")]
    assert len(set(clashing)) == 4
    assert all(re.fullmatch(r"(emil|run_all)-[0-9a-f]{16}", s) for s in clashing)


def test_a_name_equal_to_another_names_digest_stem_is_kept_apart() -> None:
    forged = safe_stem("../x")  # x-<digest>: a plain name can spell it
    stems = file_stems(["../x", forged])
    assert stems["../x"] != stems[forged]


@settings(max_examples=300, derandomize=True, database=None)
@given(st.lists(st.text(min_size=1, max_size=80), max_size=8))
def test_stems_are_plain_distinct_components(names: list[str]) -> None:
    stems = file_stems(names, reserved=["configuration", "run_all"])
    assert set(stems) == set(names)
    values = list(stems.values())
    assert len({v.lower() for v in values}) == len(values)
    for stem in values:
        assert STEM.fullmatch(stem) and len(stem) <= MAX_STEM + 65
        assert stem not in ("configuration", "run_all")
