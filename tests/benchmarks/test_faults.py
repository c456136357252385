"""The fault benchmark's link and one condition end to end (benchmarks/faults.py).

The lossy link is measured through itself: UDP echoes from one namespace to
the other (the share lost, the round trip of a delay, a cut that lets
nothing through), and the TCP proxy's delay and cut on loopback. Then one
quick condition runs end to end and prints its row. Bounded waits; every
process started here is stopped by its pid; no namespace is left behind.
"""

from __future__ import annotations

import json
import re
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from benchmarks.lossy_link import PREFIX, LinkUnavailable, NetnsLink, ProxyLink
from benchmarks.reconfigure import ROOT

ECHO_SERVER = """
import socket
s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
s.bind(("10.77.0.2", 9000))
while True:
    data, peer = s.recvfrom(100)
    s.sendto(data, peer)
"""

ECHO_CLIENT = """
import json, socket, sys, time
s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
s.settimeout(0.6)
answered, trips = 0, []
for i in range(int(sys.argv[1])):
    sent = time.monotonic()
    s.sendto(str(i).encode(), ("10.77.0.2", 9000))
    try:
        while s.recvfrom(100)[0] != str(i).encode():
            pass
        answered += 1
        trips.append(time.monotonic() - sent)
    except OSError:
        pass
print(json.dumps({"answered": answered, "trips": trips}))
"""


def _namespaces() -> list[str]:
    out = subprocess.run(["ip", "netns", "list"], capture_output=True, text=True, timeout=30)
    return [line.split()[0] for line in out.stdout.splitlines() if line.startswith(PREFIX)]


@pytest.fixture
def link() -> Iterator[NetnsLink]:
    try:
        made = NetnsLink(seed=7)
    except LinkUnavailable as error:
        pytest.skip(f"no netns link here: {error}")
    server = subprocess.Popen(made.wrap(1, [sys.executable, "-c", ECHO_SERVER]))
    try:
        time.sleep(0.3)
        yield made
    finally:
        server.kill()
        server.wait(30)
        made.close()
    assert not [n for n in _namespaces() if n in made.names]


def _echo(link: NetnsLink, count: int) -> dict[str, object]:
    client = [sys.executable, "-c", ECHO_CLIENT, str(count)]
    out = subprocess.run(link.wrap(0, client), capture_output=True, text=True, timeout=120)
    return json.loads(out.stdout)  # type: ignore[no-any-return]


@pytest.mark.slow
def test_the_namespace_link_loses_the_share_asked_delays_and_cuts(link: NetnsLink) -> None:
    """Clean: every echo comes back. 20 % loss: about 20 % of the packets
    dropped (seeded), so about 36 % of round trips fail. 100 ms delay: the
    round trip takes 200 ms and more. A cut: nothing comes back."""
    assert _echo(link, 50)["answered"] == 50
    link.set(loss=0.2)
    seen, dropped = link.counts.seen, link.counts.dropped
    answered = int(_echo(link, 300)["answered"])  # type: ignore[call-overload]
    share = (link.counts.dropped - dropped) / (link.counts.seen - seen)
    assert 0.14 < share < 0.26, share
    assert 150 < answered < 230, answered  # 300 x 0.8 x 0.8 = 192
    link.set(delay=0.1)
    trips = _echo(link, 10)["trips"]
    assert len(trips) == 10 and all(0.19 < t < 0.5 for t in trips), trips  # type: ignore[arg-type]
    link.set(loss=1.0)
    assert _echo(link, 5)["answered"] == 0
    link.set()
    assert _echo(link, 5)["answered"] == 5


@pytest.mark.slow
def test_the_proxy_link_delays_stalls_and_cuts() -> None:
    """Bytes through the proxy arrive 100 ms late under a delay; a stall holds
    them until it ends; a cut closes the connection and refuses a new one;
    after it, a connection works."""
    with socket.socket() as server:
        server.bind(("127.0.0.1", 0))
        server.listen()
        proxy = ProxyLink(target=int(server.getsockname()[1]))
        try:
            proxy.set(delay=0.1)
            with socket.create_connection(("127.0.0.1", proxy.port), timeout=5) as client:
                sent = time.monotonic()
                client.sendall(b"ping")
                accepted, _ = server.accept()
                with accepted:
                    accepted.settimeout(5)
                    assert accepted.recv(10) == b"ping"
                    assert time.monotonic() - sent >= 0.1
                    proxy.set()
                    proxy.stalled = True
                    client.sendall(b"held")
                    accepted.settimeout(0.5)
                    with pytest.raises(TimeoutError):
                        accepted.recv(10)
                    proxy.stalled = False
                    accepted.settimeout(5)
                    assert accepted.recv(10) == b"held"
                    proxy.set(loss=1.0)
                    assert accepted.recv(10) == b""  # closed by the cut
            with socket.create_connection(("127.0.0.1", proxy.port), timeout=5) as refused:
                refused.settimeout(5)
                assert refused.recv(10) == b""
            with pytest.raises(LinkUnavailable):
                proxy.set(loss=0.2)
            proxy.set()
            with socket.create_connection(("127.0.0.1", proxy.port), timeout=5) as client:
                client.sendall(b"again")
                accepted, _ = server.accept()
                with accepted:
                    accepted.settimeout(5)
                    assert accepted.recv(10) == b"again"
        finally:
            proxy.close()


@pytest.mark.slow
def test_one_condition_runs_end_to_end_and_prints_its_row() -> None:
    """``--quick --only 'frozen 0.8'``: one trial against real processes; the
    row has the trial, a detection and a recovery measured (three figures),
    and the run leaves no namespace behind."""
    before = set(_namespaces())
    command = [sys.executable, "-m", "benchmarks.faults", "--quick", "--only", "frozen 0.8"]
    out = subprocess.run(command, cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    (line,) = [x for x in out.stdout.splitlines() if x.startswith("| Pippi frozen 0.8 s |")]
    cells = [c.strip() for c in line.strip("|").split("|")]
    assert cells[1] == "1"
    assert re.fullmatch(r"\d+\.\d\d", cells[2]), cells  # detection
    assert re.fullmatch(r"\d+\.\d\d / \d+\.\d\d / \d+\.\d\d", cells[4]), cells  # recovery
    assert cells[8] in ("✓", "✗")
    assert "- link: " in out.stdout
    assert set(_namespaces()) <= before


def test_the_committed_page_was_written_by_the_benchmark() -> None:
    """docs/explanation/faults.md is what ``--markdown`` writes: the run's
    facts, the table with every condition, and how to make it again."""
    from benchmarks.fault_conditions import CONDITIONS
    from benchmarks.faults import HEADER

    text = (ROOT / "docs" / "explanation" / "faults.md").read_text(encoding="utf-8")
    assert text.startswith("<!-- Written by `python -m benchmarks.faults --markdown")
    assert "| " + " | ".join(HEADER) + " |" in text
    for condition in CONDITIONS:
        assert f"| {condition.name} |" in text, condition.name
    assert "- link: " in text and "Made with `python -m benchmarks.faults" in text


def test_the_committed_page_shows_the_link_loss_and_scale_pages_last_runs() -> None:
    """Beside its own run, the faults page shows the last runs of the
    link-loss and scale benchmarks as their pages have them (facts and
    tables): a page written again after either (``--rewrite``) keeps its own
    run and takes theirs."""
    from benchmarks.faults import LINK_LOSS_PAGE, SCALE_PAGE, last_run

    text = (ROOT / "docs" / "explanation" / "faults.md").read_text(encoding="utf-8")
    for shown in (last_run(LINK_LOSS_PAGE, 1), last_run(SCALE_PAGE, 2)):
        assert "- revision: " in shown and "\n| " in shown
        assert shown in text


def test_a_page_written_again_keeps_its_run_and_takes_the_others_anew(tmp_path: Path) -> None:
    """``--rewrite PAGE``: the page of a run, written again, is that page byte
    for byte (its facts, table and the trials over the limit kept; the other
    pages' last runs taken as they are)."""
    from benchmarks.fault_conditions import Options
    from benchmarks.faults import page, rewrite

    facts = ["- machine: m", "- revision: `abc`"]
    lines = ["| a | b |", "|---|---|", "| 1 | 2 |"]
    evidence = [
        "- 50 % loss, trial 3:\n    +3.54s robot-lost other=Pippi",
        "- cut, trial 1:\n    +1s x",
    ]
    command = ["--trials", "3", "--markdown", "faults.md"]
    written = page(Options(), lines, facts, evidence, command)
    path = tmp_path / "faults.md"
    path.write_text(written.replace("## Beyond one helper", "## Old words\n\n## Beyond one helper"))
    rewrite(path)
    assert path.read_text() == written


def test_a_row_misses_the_limit_on_one_late_trial_a_stop_or_a_light_switch() -> None:
    """The ✓/✗ column: ✓ only when every trial recovered within hold + 1 s
    (2 s here); one late trial, one permanent stop (no recovery), or a switch
    under a light condition is ✗; a row without trials is n/a."""
    from benchmarks.fault_conditions import CONDITIONS, Options, Trial
    from benchmarks.faults import row

    freeze, light = CONDITIONS[1], next(c for c in CONDITIONS if c.light)
    options = Options()
    good = Trial(detection=0.1, switch=0.3, recovery=0.7, served=0.0)
    assert row(freeze, [good, good], options)[-1] == "✓"
    assert row(freeze, [good, Trial(recovery=2.3)], options)[-1] == "✗"
    stopped = row(freeze, [good, Trial(detection=0.1)], options)
    assert stopped[-1] == "✗" and stopped[6] == "1/2" and stopped[4] == "0.70 / 0.70 / 0.70"
    assert row(light, [Trial(recovery=0.1, spurious=2)], options)[-1] == "✗"
    assert row(light, [], options)[-1] == "n/a"
