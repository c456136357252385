"""No split brain: a second process of a live robot, or a second coordinator,
is refused and ends; the society goes on (5.5).

Cross-door step 2 (6.2.2), each robot its own process: Emil owns the goal and
coordinates, Pippi helps. A second process started as Pippi ends with exit
status 1 and says why; so does a second process started as Emil (a second
coordinator), told by Pippi that she follows the first. The goal is served
throughout, and the first Pippi's death is still seen afterwards (two
processes of one name share one liveliness token: the second one would have
hidden it). Before, a second Emil silently took Pippi over. Hermetic:
loopback, free ports, scouting off, bounded waits, every process stopped by
its pid (:mod:`tests.runtime.netutil`).
"""

from __future__ import annotations

import os
import signal
import time
from pathlib import Path

import pytest

from tests.backends.support import EXAMPLE_IMPL
from tests.reconfigure.test_network import LIMIT, _robot
from tests.reconfigure.test_network_restart import SERVED_FIELDS, _after, served_step2
from tests.runtime.netutil import endpoint, free_port, processes, read_trace, wait_for


@pytest.mark.slow
def test_a_second_pippi_and_a_second_emil_are_refused_and_the_goal_is_served(
    tmp_path: Path,
) -> None:
    served = SERVED_FIELDS
    with processes() as running:
        pippi, emil_trace, pippi_net = served_step2(running, tmp_path, "twins-test")
        said = {}
        pippi_at, emil_at = pippi_net[1], pippi_net[3]  # --listen P --connect E
        for name, at in (("Pippi", emil_at), ("Emil", pippi_at)):
            folder = tmp_path / f"second-{name}"
            folder.mkdir()
            # the second Emil reaches Pippi only, as a second coordinator would
            network = ["--listen", endpoint(free_port()), "--connect", at, *pippi_net[4:]]
            twin, _ = _robot(running, folder, name, EXAMPLE_IMPL, network)
            assert twin.wait(timeout=LIMIT) == 1  # type: ignore[attr-defined]
            said[name] = (folder / f"{name.lower()}.log").read_text()
            t = time.time()
            wait_for("the goal still served", _after(emil_trace, t, "call", **served), LIMIT)
        killed = time.time()
        os.kill(pippi.pid, signal.SIGKILL)  # type: ignore[attr-defined]
        lost = wait_for("the first Pippi's death seen", _after(emil_trace, killed, "failure"), 10)
        running.stop_all()
    assert lost["resource"] == "Pippi" and lost["how"] == "lost"
    assert (
        "cfgplan: error: another process runs robot Pippi in society twins-test "
        "(the coordinator, Emil, keeps it): this one stops"
    ) in said["Pippi"]
    assert (
        "cfgplan: error: society twins-test has a coordinator already: "
        "Pippi follows Emil; this one stops"
    ) in said["Emil"]
    mine = read_trace(emil_trace)
    assert [r["resource"] for r in mine if r["event"] == "failure"] == ["Pippi"]
    errors = [r["message"] for r in mine if r["event"] == "error"]
    assert errors == [
        "a second process of robot Pippi: dropped",
        "a second coordinator of the society, refused by Pippi: dropped",
    ]
