"""``cfgplan plan``: formats, exit codes, determinism (thesis 4.4-4.6)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tests.cli.conftest import ROOT, Run

CROSS = ("domains/cross-door/domain.lisp", "domains/cross-door/state-6.2.2-step1.lisp")
MEDIA = ("domains/cross-door/domain-bandwidth.lisp", "domains/cross-door/state-4.6-media.lisp")
WALL = ("domains/build-wall/domain.lisp", "domains/build-wall/state-6.4.lisp")


def test_table_lists_ranked_costs(cfgplan: Run) -> None:
    out = cfgplan("plan", *CROSS)
    assert out.returncode == 0, out.stderr
    rows = [line for line in out.stdout.splitlines() if line.startswith("│")]
    assert [r.split("│")[2].strip() for r in rows] == ["44", "47"]
    assert "communication admissibility not checked" in out.stdout


def test_json_schema_and_values(cfgplan: Run) -> None:
    """The public JSON interface (README, 'JSON output') on section 4.6."""
    out = cfgplan("plan", *MEDIA, "--format", "json", "-k", "1")
    assert out.returncode == 0, out.stderr
    doc = json.loads(out.stdout)
    assert list(doc) == ["goal", "configurations", "communication_checked", "media", "stats"]
    assert doc["goal"] == "do-cross-door(Pippi, Door1)"
    assert doc["communication_checked"] is True
    assert doc["media"] == [  # the state's media, in order: channels name them by index
        {"type": "socket", "from": "Pippi", "to": "Emil", "capacity": 200, "reliability": None},
        {"type": "socket", "from": "Emil", "to": "Pippi", "capacity": 200, "reliability": None},
    ]
    assert doc["stats"]["more"] is True  # -k 1 cut the list: 47 exists too
    (config,) = doc["configurations"]
    assert (config["rank"], config["cost"]) == (1, 44)
    assert set(config["robots"]) == {"Pippi", "Emil"}
    assert set(config["functionalities"][0]) == {"id", "name", "args", "robot"}
    channel = config["channels"][-1]
    assert channel == {
        "kind": "global",
        "from": "F7",
        "to": "F3",
        "from_robot": "Emil",
        "to_robot": "Pippi",
        "data": ["orient", "Pippi", "Door1"],
        "bandwidth": 10,
        "medium": 1,
    }
    assert config["media_loads"] == [10, 30]  # 4.6: global-orient 10; pos 20 + orient 10


def test_json_without_media_leaves_the_media_keys_out(cfgplan: Run) -> None:
    """README, 'JSON output': no media declared, no ``media`` and no
    ``media_loads`` (rather than empty lists), and communication not checked."""
    out = cfgplan("plan", *CROSS, "--format", "json")
    assert out.returncode == 0, out.stderr
    doc = json.loads(out.stdout)
    assert list(doc) == ["goal", "configurations", "communication_checked", "stats"]
    assert doc["communication_checked"] is False
    assert [c["cost"] for c in doc["configurations"]] == [44, 47]
    assert all("media_loads" not in c for c in doc["configurations"])
    assert all(ch["medium"] is None for c in doc["configurations"] for ch in c["channels"])


@pytest.mark.slow
def test_json_is_byte_identical_across_runs(cfgplan: Run) -> None:
    """Determinism: the same input gives the same bytes, whatever the hash seed."""
    a = cfgplan("plan", *WALL, "--all", "--format", "json", env={"PYTHONHASHSEED": "1"})
    b = cfgplan("plan", *WALL, "--all", "--format", "json", env={"PYTHONHASHSEED": "987"})
    assert a.returncode == b.returncode == 0
    assert a.stdout == b.stdout
    assert len(json.loads(a.stdout)["configurations"]) == 100


def test_derivations_counts_as_the_thesis(cfgplan: Run) -> None:
    """Section 6.4: --derivations --all lists 128."""
    out = cfgplan("plan", *WALL, "--derivations", "--all", "--format", "json")
    doc = json.loads(out.stdout)
    assert len(doc["configurations"]) == 128
    assert doc["stats"]["duplicates"] == 0


def test_lisp_format_is_the_thesis_description(cfgplan: Run) -> None:
    """Section 4.6's configuration description, with the media loads."""
    out = cfgplan("plan", *MEDIA, "--format", "lisp", "-k", "1")
    assert out.returncode == 0
    text = out.stdout
    assert "    global(Emil, Pippi, F7, F3, pos(Pippi, Door1), 20)" in text
    assert "    local(Emil, F8, F14, image(Emil))" in text
    assert "medium(socket, Emil, Pippi, 200): load 30" in text
    assert text.rstrip().endswith("Cost: 44\n)")


def test_weights_change_the_ranking(cfgplan: Run) -> None:
    out = cfgplan(
        "plan", *CROSS, "--weights", "robot=0,global=0,local=0,functionality=1", "--format", "json"
    )
    doc = json.loads(out.stdout)
    assert [c["cost"] for c in doc["configurations"]] == [8, 9]


def test_bad_weights_is_usage_error(cfgplan: Run) -> None:
    out = cfgplan("plan", *CROSS, "--weights", "robots=3")
    assert out.returncode == 2
    assert "bad weight 'robots=3'" in out.stderr


def test_nothing_admissible_exit_3_with_reason(cfgplan: Run) -> None:
    """Section 6.2.2 step 3 as printed: exit 3, the failed (in Door1 ?room) named."""
    out = cfgplan(
        "plan",
        "domains/cross-door/domain.lisp",
        "domains/cross-door/state-6.2.2-step3-as-printed.lisp",
    )
    assert out.returncode == 3
    assert out.stdout == ""
    assert (
        "get-door-info(Pippi, Door1), version 1 (domains/cross-door/domain.lisp:41:" in out.stderr
    )
    assert "no fact matches (in Door1 ?room) with ?room = Room2" in out.stderr


def test_goal_option_overrides_the_state(cfgplan: Run) -> None:
    out = cfgplan("plan", *CROSS, "--goal", "do-cross-door(Emil, Door1)", "--format", "json")
    assert json.loads(out.stdout)["goal"] == "do-cross-door(Emil, Door1)"


@pytest.mark.slow
def test_bad_goal_is_input_error_with_caret(cfgplan: Run) -> None:
    """The '(' never closed is the user's, not the one of the (goal ...) the
    option is read in (a newcomer was pointed at "the '(' at line 1, column 1")."""
    out = cfgplan("plan", *CROSS, "--goal", "(do-cross-door Pippi")
    assert out.returncode == 1
    assert out.stderr.splitlines() == [
        "--goal:1:7: error: a list is not closed (missing ')')",
        "    1 | (goal (do-cross-door Pippi)",
        "      |       ^",
        "  hint: every '(' needs a matching ')': this one is never closed",
    ]
    inner = cfgplan("plan", *CROSS, "--goal", "(do-cross-door Pippi Door1)", "--goal", "(x (y")
    assert inner.returncode == 1 and inner.stderr.startswith("--goal:2:7: error: a list is not")


def test_a_latin_1_byte_is_shown_where_it_stands(cfgplan: Run, tmp_path: Path) -> None:
    """The message quotes the line, the bad byte shown as U+FFFD, with a caret
    under it (a newcomer's Latin-1 state had the place but no line and no caret)."""
    state = tmp_path / "latin1.lisp"
    state.write_bytes(
        b"(state (robot Pippi)\r\n  (in Pippi Caf\xe9))\n(goal (do-cross-door Pippi Door1))\n"
    )
    out = cfgplan("plan", CROSS[0], str(state))
    assert out.returncode == 1
    assert out.stderr.splitlines()[:3] == [
        f"{state}:2:16: error: invalid UTF-8 byte 0xe9",
        "    2 |   (in Pippi Caf\ufffd))",
        "      |                ^",
    ]


def test_missing_file_is_input_error(cfgplan: Run) -> None:
    out = cfgplan("plan", "nope.lisp", CROSS[1])
    assert out.returncode == 1
    assert "no such file: nope.lisp" in out.stderr


@pytest.mark.slow
def test_output_file_is_not_overwritten_without_force(cfgplan: Run, tmp_path: Path) -> None:
    target = tmp_path / "out.json"
    target.write_text("keep me")
    refused = cfgplan("plan", *CROSS, "--format", "json", "-o", str(target))
    assert refused.returncode == 1
    assert target.read_text() == "keep me"
    forced = cfgplan("plan", *CROSS, "--format", "json", "-o", str(target), "--force")
    assert forced.returncode == 0
    assert json.loads(target.read_text())["configurations"][0]["cost"] == 44


def test_help_documents_every_option(cfgplan: Run) -> None:
    out = cfgplan("plan", "--help")
    for option in (
        "--goal",
        "-k",
        "--all",
        "--derivations",
        "--weights",
        "--format",
        "--details",
        "--verbose",
        "--time-limit",
        "--output",
        "--force",
    ):
        assert option in out.stdout, option


def test_verbose_goes_to_stderr(cfgplan: Run) -> None:
    out = cfgplan("plan", *CROSS, "--format", "json", "--verbose")
    json.loads(out.stdout)  # stdout stays pure JSON
    assert "search:" in out.stderr


def test_readme_quick_start_example_exists() -> None:
    readme = (ROOT / "README.md").read_text()
    assert "cfgplan plan domains/cross-door/domain.lisp" in readme


def test_self_loop_is_a_cycle_not_a_traceback(cfgplan: Run, tmp_path: Path) -> None:
    """A channel from a method instance to itself (``?f1 ?f1``) is
    re-wired at both ends into a functionality feeding itself: a cycle (5.1),
    so nothing is admissible: exit 3 and the cycle named (before: a KeyError
    traceback with exit 1)."""
    from tests.planner.test_reproducers import SELF_LOOP

    (tmp_path / "d.lisp").write_text(SELF_LOOP)
    (tmp_path / "s.lisp").write_text("(state (robot r1)) (goal (do r1))\n")
    out = cfgplan("plan", str(tmp_path / "d.lisp"), str(tmp_path / "s.lisp"))
    assert out.returncode == 3, out.stderr
    assert "Traceback" not in out.stderr
    assert "cycle: configuration: its channels form a cycle through F5 flt(r1)" in out.stderr


def test_json_when_nothing_is_admissible_is_still_a_document(cfgplan: Run) -> None:
    """One JSON document on stdout, the explanation as data, exit 3."""
    out = cfgplan(
        "plan",
        "domains/cross-door/domain.lisp",
        "domains/cross-door/state-6.2.2-step3-as-printed.lisp",
        "--format",
        "json",
    )
    assert out.returncode == 3
    doc = json.loads(out.stdout)
    assert doc["configurations"] == []
    dead = doc["explanation"]["dead_ends"]
    first = next(d for d in dead if d["where"] == "get-door-info(Pippi, Door1), version 1")
    assert first["condition"] == "precondition"
    assert first["failed"] == "(in Door1 ?room)"
    assert first["bindings"] == {"?room": "Room2"}
    assert first["source"].startswith("domains/cross-door/domain.lisp:41:")


def test_table_says_when_more_configurations_exist(cfgplan: Run) -> None:
    cut = cfgplan("plan", *CROSS, "-k", "1")
    assert "note: at least one more configuration exists: -k 11 lists up to 11" in cut.stdout
    whole = cfgplan("plan", *CROSS, "-k", "2")
    assert "more configuration" not in whole.stdout


def test_the_solver_engine_lists_what_the_search_lists_first(cfgplan: Run) -> None:
    """``--engine solver`` (-k 1): the configuration the search lists first, the
    cost-44 one of 6.2.2 step 1 (Fig. 6.3), byte for byte in JSON but for the
    search's statistics; without -k 1 it is a usage error (exit 2)."""
    searched = cfgplan("plan", *CROSS, "-k", "1", "--format", "json")
    solved = cfgplan("plan", *CROSS, "-k", "1", "--format", "json", "--engine", "solver")
    assert solved.returncode == 0, solved.stderr
    by_search, by_solver = json.loads(searched.stdout), json.loads(solved.stdout)
    assert by_solver["configurations"] == by_search["configurations"]
    assert by_solver["configurations"][0]["cost"] == 44
    assert by_solver["stats"]["more"] is None  # the solver does not look for a second
    table = cfgplan("plan", *CROSS, "-k", "1", "--engine", "solver")
    assert "44" in table.stdout and "more configuration" not in table.stdout  # nor claims one
    for more in ([], ["--all"], ["-k", "2"], ["--rank", "2"]):
        wrong = cfgplan("plan", *CROSS, "--engine", "solver", *more)
        assert wrong.returncode == 2 and "-k 1" in wrong.stderr, more
    steps = ("domains/cross-door/domain-steps.lisp", "domains/cross-door/state-6.2.2-sequence.lisp")
    sequence = cfgplan("plan", *steps, "-k", "1", "--engine", "solver")
    assert sequence.returncode == 2 and "sequence" in sequence.stderr


def test_the_default_race_within_its_budget_is_the_search_to_the_byte(cfgplan: Run) -> None:
    """``-k 1`` races the solver only past the search's budget (--engine both,
    the default): 6.2.2 step 1 (Fig. 6.3, cost 44) ends long before, so the
    table (its "more exist" note included) and the JSON (work counts included)
    are the search's, byte for byte."""
    for shown in ([], ["--format", "json"]):
        both = cfgplan("plan", *CROSS, "-k", "1", *shown)
        alone = cfgplan("plan", *CROSS, "-k", "1", "--engine", "search", *shown)
        assert both.returncode == alone.returncode == 0, both.stderr
        assert both.stdout == alone.stdout
    assert json.loads(both.stdout)["stats"]["engine"] == "search"


@pytest.mark.slow
def test_past_the_searchs_cliff_the_default_race_is_answered_by_the_solver(
    cfgplan: Run, tmp_path: Path
) -> None:
    """``structured`` seed 2 with 16 pieces: the search alone takes about 13 s
    (docs/explanation/planner.md), the solver about one; ``cfgplan plan -k 1``
    answers with the solver's process, the configuration ``--engine solver``
    finds (the search's first), and says so in the JSON; no second is looked
    for, so the JSON's more is null and the table claims nothing about more."""
    from benchmarks.families import structured

    domain, state = tmp_path / "domain.lisp", tmp_path / "state.lisp"
    for path, text in zip((domain, state), structured(2, pieces=16), strict=True):
        path.write_text(text, encoding="utf-8")
    raced = cfgplan("plan", str(domain), str(state), "-k", "1", "--format", "json")
    solved = cfgplan("plan", str(domain), str(state), "-k", "1", "--format", "json",
                     "--engine", "solver")  # fmt: skip
    assert raced.returncode == solved.returncode == 0, raced.stderr
    by_race, by_solver = json.loads(raced.stdout), json.loads(solved.stdout)
    assert by_race["configurations"] == by_solver["configurations"]
    assert by_race["stats"]["engine"] == "solver" and by_race["stats"]["more"] is None
    table = cfgplan("plan", str(domain), str(state), "-k", "1")
    assert f"│ {by_race['configurations'][0]['cost']:g} │" in table.stdout.replace("  ", " ")
    assert "more configuration" not in table.stdout
