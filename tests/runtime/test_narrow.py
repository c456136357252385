"""A robot that follows and may never coordinate watches only the robots it needs
(``ZenohTransport.narrow``): among 50 robots behind a router, a loss or a return
was news to every process, 49 of which woke for it at once while the coordinator
switched. In one process: a router, the coordinator Vacu and helpers H1-H3 as
its clients."""

from __future__ import annotations

import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from cfgplan.runtime.router import RouterOptions, serve
from cfgplan.runtime.zenoh_transport import ZenohOptions, ZenohTransport
from cfgplan.security.identity import ProblemId
from tests.runtime.netutil import Record, endpoint, free_port, hermetic_config, wait_for

LIMIT = 30.0
MINE = ProblemId("00112233445566aa", "docking with state.lisp, goal do-dock(Vacu, Charger1)")
THEIRS = ProblemId("0123456789abcdef", "another problem")


@contextmanager
def _router(config: str) -> Iterator[str]:
    """A router on a free loopback port (its endpoint), stopped at the end."""
    where = endpoint(free_port())
    stop, listening = threading.Event(), threading.Event()
    options = RouterOptions((where,), 1.0, config)
    said = lambda line: listening.set()  # noqa: E731  ("router ... listening on ...")
    thread = threading.Thread(target=serve, args=(options, said, stop), daemon=True)
    thread.start()
    try:
        assert listening.wait(LIMIT), "the router did not open"
        yield where
    finally:
        stop.set()
        thread.join(LIMIT)


def _until(what: str, holds: object) -> None:
    def found() -> Record | None:
        return {"ok": True} if holds() else None  # type: ignore[operator]

    wait_for(what, found, LIMIT)


def test_a_narrowed_helper_hears_of_the_robots_it_watches_only(tmp_path: Path) -> None:
    """H1 watches Vacu (who may coordinate), its partner H2 and, once it
    follows it, any other coordinator; H3's coming and going never reaches
    it, while H2 (not narrowed) hears of everyone. Having met Vacu, of its
    own problem, H1 drops the problem tokens: a robot of another problem is
    said by H2, not by H1."""
    config = str(hermetic_config(tmp_path))
    with _router(config) as where:
        opened: list[ZenohTransport] = []

        def client(name: str, problem: ProblemId = MINE) -> ZenohTransport:
            options = ZenohOptions("narrow", config_file=config, problem=problem, router=(where,))
            opened.append(ZenohTransport(name, options))
            return opened[-1]

        try:
            vacu, h1, h2 = client("Vacu"), client("H1"), client("H2")
            h1.narrow(["Vacu"])
            heard: list[tuple[str, bool]] = []
            h1.watch("H1", ["H2"], lambda name, alive: heard.append((name, alive)))
            told: list[tuple[str, bool]] = []
            h1.presence_listeners.append(lambda name, alive: told.append((name, alive)))
            h2.watch("H2", ["H1"], lambda name, alive: None)
            h3 = client("H3")

            def polled(*names: str) -> bool:
                for t in (vacu, h1, h2):
                    t.poll()
                return all(n in h2.alive for n in names)

            _until("H2 sees everyone", lambda: polled("Vacu", "H1", "H3"))
            _until("H1 sees Vacu and H2", lambda: polled() and h1.alive == {"Vacu", "H2"})
            said: dict[str, list[str]] = {"H1": [], "H2": []}
            h1.notices.append(lambda message, channel: said["H1"].append(message))
            h2.notices.append(lambda message, channel: said["H2"].append(message))
            h3.close()
            opened.remove(h3)
            _until("H2 sees H3 lost", lambda: polled() and "H3" not in h2.alive)
            eve = client("Eve", THEIRS)
            _until("H2 says Eve is not of its society", lambda: polled() and said["H2"])
            time.sleep(0.5)  # what reaches H1 (nothing should) has reached it
            polled()
            assert said["H1"] == []  # H1, a member since it met Vacu, no longer watches
            assert "H3" not in h1.alive and "Eve" not in h1.alive
            assert {name for name, _ in told} <= {"Vacu", "H2"}
            assert ("H2", True) in heard  # its partner, reported to its robot
            h1.watch_robot("Eve")  # the coordinator it now follows, say
            _until("H1 sees Eve once it watches her", lambda: polled() and "Eve" in h1.alive)
            assert ("Eve", True) in told
            eve.close()
            opened.remove(eve)
            _until("H1 sees Eve lost", lambda: polled() and ("Eve", False) in told)
        finally:
            for transport in opened:
                transport.close()
