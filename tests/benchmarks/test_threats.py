"""The threat model's benchmark (benchmarks/threats.py): every test a threat
names exists, a run's report is read case by case with what each recorded,
every attack the team measured on the society is on the list, and the
committed page is what ``--markdown`` writes. Nothing is started here: the
benchmark runs the tests itself."""

from __future__ import annotations

import ast
from pathlib import Path

from benchmarks.reconfigure import ROOT
from benchmarks.threats import (
    HEADER,
    THREATS,
    keyed_rows,
    labels,
    listed_tests,
    node_ids,
    outcomes,
    threat_rows,
)


def test_every_test_a_threat_names_is_a_test_of_its_file() -> None:
    for node in node_ids():
        path, name = node.split("::")
        tree = ast.parse((ROOT / path).read_text(encoding="utf-8"))
        defined = {f.name for f in tree.body if isinstance(f, ast.FunctionDef)}
        assert name in defined, node
    assert all(t.refused or t.limits for t in THREATS)  # each says what refuses or bounds it


def test_every_attack_measured_on_the_society_is_listed() -> None:
    """The attacks a member's key made that stopped or stalled a society (a
    forged rival, a problem token, a flood of the control key), the weaker
    ones beside them (a name held alive, a raw session, the live page's
    streams held, a trace readable by others, a NaN in a trace), strangers,
    and the secured router's own."""
    said = " ".join(t.attack for t in THREATS).lower()
    for attack in (
        "forged rival",
        "problem token",
        "flood of its key to the coordinator",
        "liveliness token held up",
        "raw session",
        "every stream of the live page",
        "reads a trace",
        "nan",
        "stranger",
        "router's key",
        "second coordinator",
    ):
        assert attack in said, attack


def test_a_report_is_read_case_by_case_with_what_each_recorded(tmp_path: Path) -> None:
    first, second = node_ids()[0], node_ids()[1]
    module = first.split("::")[0][:-3].replace("/", ".")
    other = second.split("::")[0][:-3].replace("/", ".")
    report = tmp_path / "report.xml"
    report.write_text(
        f"""<?xml version="1.0" encoding="utf-8"?>
<testsuites><testsuite name="pytest">
<testcase classname="{module}" name="{first.split("::")[1]}" time="30.5">
  <properties><property name="messages a second sent" value="41000"/></properties>
</testcase>
<testcase classname="{other}" name="{second.split("::")[1]}[keys]" time="2.0">
  <failure message="boom">boom</failure>
</testcase>
<testcase classname="{other}" name="{second.split("::")[1]}[open]" time="1.0"/>
<testcase classname="tests.elsewhere" name="test_other" time="9"/>
</testsuite></testsuites>
""",
        encoding="utf-8",
    )
    found = outcomes(report)
    assert found[first].passed and found[first].seconds == 30.5
    assert found[first].figures == [("", "messages a second sent", "41000")]
    assert not found[second].passed and found[second].cases == [("keys", False), ("open", True)]
    assert not any(o.cases for n, o in found.items() if n not in (first, second))
    lines = listed_tests(found)
    assert lines[0] == (
        f"- T1 `{first}`: passed 1 of 1 in 30 s; it recorded messages a second sent 41000"
    )
    assert lines[1] == f"- T2 `{second}`: passed 1 of 2 (keys, open) in 3 s"
    assert lines[2].endswith(": not run")
    rows = threat_rows(found)
    assert rows[0][2] == f"{labels()[first]} ✓, {labels()[THREATS[0].tests[1]]} ✗"
    unrefused = next(r for t, r in zip(THREATS, rows, strict=True) if not t.refused)
    assert unrefused[1].startswith(("**not refused**", "*keys*: **not refused**"))


def test_the_keyed_sizes_of_the_scale_page_are_shown_with_and_without_keys(tmp_path: Path) -> None:
    page = tmp_path / "scale.md"
    up = "| robots | topology | up |\n|---|---|---|\n"
    kills = "| robots | topology | kills |\n|---|---|---|\n"
    page.write_text(
        f"# x\n\n## The last run\n\n- machine: m\n\n{up}| 2 | router | 1 |\n| 3 | router | 2 |\n"
        f"| 3 | router + keys | 3 |\n| 3 | mesh | 4 |\n\n"
        f"{kills}| 3 | router | 5 |\n| 3 | router + keys | 5 |\n"
    )
    assert keyed_rows(page) == (
        f"- machine: m\n\n{up}| 3 | router | 2 |\n| 3 | router + keys | 3 |\n\n"
        f"{kills}| 3 | router | 5 |\n| 3 | router + keys | 5 |"
    )


def test_the_committed_page_was_written_by_the_benchmark() -> None:
    text = (ROOT / "docs" / "explanation" / "threat-model.md").read_text(encoding="utf-8")
    assert text.startswith("<!-- Written by `python -m benchmarks.threats")
    assert "| " + " | ".join(HEADER) + " |" in text
    for threat in THREATS:
        assert f"| {threat.attack} |" in text, threat.attack
    assert "- machine: " in text and "Made with `python -m benchmarks.threats" in text
    assert "✗" not in text, "a threat's test failed in the run the page shows"
