"""The link-loss benchmark (benchmarks/link_loss.py): a trial's figures from
the coordinator's trace, each topology's network options, and the committed
page is what ``--markdown`` writes. The trials themselves (network namespaces,
real processes, 30 s of loss each) run in the benchmark, not here."""

from __future__ import annotations

from pathlib import Path

from benchmarks.link_loss import HEADER, measure, network, rewrite, row
from benchmarks.lossy_link import NetnsLink
from benchmarks.reconfigure import ROOT


def _call(t: float) -> dict[str, object]:
    return {"event": "call", "t": t, "functionality": "lead-robot", "status": "ran"}


def test_a_trial_counts_the_healthy_robots_loss_the_longest_stop_and_the_service() -> None:
    pippi = [
        _call(100.0),
        {"event": "robot-lost", "t": 101.0, "other": "Emil"},
        {"event": "switch", "t": 101.0, "cause": "Emil failed"},
        *(_call(101.0 + k / 10) for k in range(1, 50)),  # 49 cycles served of the loss's 100
        {"event": "failure", "t": 106.0, "resource": "Rasmus"},
        {"event": "no-configuration", "t": 106.0, "cause": "Rasmus failed"},
        {"event": "switch", "t": 108.5, "cause": "Rasmus recovered"},
        _call(111.0),
    ]
    trial = measure(pippi, began=100.5, healed=110.5)
    assert trial.healthy_lost and trial.lossy_lost
    assert trial.stopped == 2.5
    assert trial.served == 0.49
    assert "+5.50s no-configuration Rasmus failed" in trial.events
    calm = measure([_call(100.0), {"event": "robot-lost", "t": 101.0, "other": "Emil"}], 100, 110)
    assert not calm.healthy_lost and calm.lossy_lost and calm.stopped == 0.0
    assert row("router", [trial, calm])[2:5] == ["1/2", "2.5 s", "2/2"]


def test_the_router_topology_gives_each_robot_one_link_the_mesh_every_other() -> None:
    link = NetnsLink.__new__(NetnsLink)  # the addresses only: no namespace is made
    link.addresses = ("10.77.0.1", "10.77.0.2")
    routed = network("router", link)
    assert all(args == ["--router", "tcp/10.77.0.1:7447"] for args in routed.values())
    meshed = network("mesh", link)
    assert meshed["Emil"][:2] == ["--listen", "tcp/10.77.0.2:7447"]
    assert meshed["Emil"].count("--connect") == 2 and meshed["Rasmus"].count("--connect") == 1


def test_the_committed_page_was_written_by_the_benchmark() -> None:
    text = (ROOT / "docs" / "explanation" / "link-loss.md").read_text(encoding="utf-8")
    assert text.startswith("<!-- Written by `python -m benchmarks.link_loss")
    assert "| " + " | ".join(HEADER) + " |" in text
    assert "| router" in text and "| mesh" in text  # alone, or beside a baseline
    assert "- link: " in text and "Made with `python -m benchmarks.link_loss" in text


def test_rewrite_puts_the_modules_words_around_the_run_it_keeps(tmp_path: Path) -> None:
    """``--rewrite PAGE``: the words before the run are this module's, for the
    command that made the page; the run (facts, table, evidence) is kept."""
    shown = "python -m benchmarks.link_loss --trials 2 --loss 0.2 --markdown x.md"
    run = "- date: then\n\n| a |\n|---|\n| 1 |\n\nMade with `" + shown + "`; run it again.\n"
    page = tmp_path / "link-loss.md"
    page.write_text(f"<!-- old -->\n\n# Loss on one link\n\nold words\n## The last run\n\n{run}")
    rewrite(page)
    text = page.read_text(encoding="utf-8")
    assert "old words" not in text and text.endswith("## The last run\n\n" + run)
    assert "drops 20% of the packets" in text and "runs 2 times" in text
    assert text.startswith(f"<!-- Written by `{shown}`")
