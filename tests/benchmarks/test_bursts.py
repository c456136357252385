"""``python -m benchmarks.bursts``: the table of messages sent in bursts of three.

With congestion control *block* Zenoh waits for room in the link's queue,
so every message sent arrives (the *drop* row may lose some on a loaded
machine: what the switch protocol's telling again makes up for,
docs/explanation/switch-protocol.md). Loopback, free ports, scouting off;
the receiver is stopped by its pid.
"""

from __future__ import annotations

import pytest

from benchmarks import bursts


@pytest.mark.slow
def test_every_message_sent_with_block_arrives(capsys: pytest.CaptureFixture[str]) -> None:
    bursts.main(["--bursts", "20", "--rounds", "1"])
    rows = {
        cells[1]: cells[2:]
        for line in capsys.readouterr().out.splitlines()
        if line.startswith("| ") and (cells := [c.strip() for c in line.split("|")])[1] != "---"
    }
    assert rows["block"][:3] == ["1", "60", "60"], rows
    drop = int(rows["drop"][2])
    assert 0 <= drop <= 60, rows
