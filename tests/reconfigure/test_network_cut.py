"""A link cut for 5 s through a TCP proxy: the society serves its goal again by
itself within hold + 1 s of the link coming back (5.5).

Cross-door step 2 (6.2.2), each robot its own process: Emil owns the goal and
coordinates, Pippi helps and reaches him only through a TCP proxy on
loopback (:class:`benchmarks.lossy_link.ProxyLink`). The proxy closes every
connection and refuses new ones for 5 s: Emil loses Pippi and stops the
crossing (every configuration needs her); then the proxy lets connections
through again, Pippi reconnects (she retries every second at most), says
she is ready, and the goal's action runs on her data again. Hermetic:
loopback, free ports, scouting off, bounded waits, every process stopped by
its pid (:mod:`tests.runtime.netutil`).
"""

from __future__ import annotations

import time
from pathlib import Path

import pytest

from benchmarks.lossy_link import ProxyLink
from tests.backends.support import EXAMPLE_IMPL
from tests.reconfigure.test_network import LIMIT, _network, _robot
from tests.reconfigure.test_network_restart import SERVED_FIELDS, _after
from tests.runtime.netutil import processes, read_trace, wait_for

HOLD = 1.0  # cfgplan run's default hysteresis hold (--hold)


@pytest.mark.slow
def test_a_link_cut_for_5_s_heals_by_itself(tmp_path: Path) -> None:
    emil_net, pippi_net = _network(tmp_path, "cut-test")
    emil_port = int(emil_net[1].rsplit(":", 1)[1])  # --listen tcp/127.0.0.1:PORT
    link = ProxyLink(target=emil_port)
    pippi_net[3] = f"tcp/127.0.0.1:{link.port}"  # --connect through the proxy
    try:
        with processes() as running:
            _, emil_trace = _robot(
                running, tmp_path, "Emil", EXAMPLE_IMPL, emil_net, "--duration", "120"
            )
            _robot(running, tmp_path, "Pippi", EXAMPLE_IMPL, pippi_net)
            wait_for("the goal served", _after(emil_trace, 0.0, "call", **SERVED_FIELDS), LIMIT)
            time.sleep(1.0)
            cut = time.time()
            link.set(loss=1.0)
            lost = wait_for("Pippi lost", _after(emil_trace, cut, "failure"), LIMIT)
            time.sleep(max(0.0, cut + 5.0 - time.time()))
            link.set(loss=0.0)
            back = time.time()
            again = wait_for(
                "the goal again", _after(emil_trace, back, "call", **SERVED_FIELDS), LIMIT
            )
            running.stop_all()
    finally:
        link.close()
    assert (lost["resource"], lost["how"]) == ("Pippi", "lost")
    assert float(again["t"]) - back < HOLD + 1.0  # type: ignore[arg-type]
    mine = read_trace(emil_trace)
    stops = [r for r in mine if r["event"] == "no-configuration" and float(r["t"]) > back]  # type: ignore[arg-type]
    assert stops == []  # once back, served: no stop after the link returned
