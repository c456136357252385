"""``cfgplan run ... --live [HOST:]PORT``: the live page beside a run.

:func:`open_live` subscribes a :class:`~cfgplan.live.watch.Watch` to the
society, starts the :class:`~cfgplan.live.server.LiveServer` on a thread of
its own and prints the page's URL; the caller stops it when the run ends
(:meth:`~cfgplan.live.server.LiveServer.stop`, bounded).

What the page shows depends on which robots run in this process. With every
robot here (``cfgplan run`` without ``--robot``), or on the coordinator (the
robot that owns the goal), it shows the whole society as the coordinator
knows it: every switch, failure and recovery, the fallbacks. On another
robot (``--robot NAME``, not the coordinator) it shows that robot's view: its
own channels' freshness, the robots it exchanges data with, the faults
injected there and the configurations it installs; the drawing stays the
first configuration, and the fallbacks are the coordinator's to show. A
robot that takes over coordination shows the society from then on (its
switches, its drawing, its fallbacks); one that steps down, its own view
again (its drawing the last configuration it coordinated).
"""

from __future__ import annotations

import time

from cfgplan.configuration.model import Configuration
from cfgplan.live.address import Address
from cfgplan.problem import Problem
from cfgplan.reconfigure.owner import coordinator_of
from cfgplan.reconfigure.succession import Shown, coordinating
from cfgplan.runtime.errors import RunError
from cfgplan.runtime.launch import Hooks
from cfgplan.runtime.society import Society

__all__ = ["INSTALL_HINT", "Live", "open_live"]

INSTALL_HINT = "pip install 'cfgplan[live]'"


class Live:
    """A running live page: its URL, and :meth:`stop`."""

    def __init__(self, server: object, url: str) -> None:
        self._server = server
        self.url = url

    def stop(self) -> None:
        """Stop the page's server (bounded: a few seconds at most)."""
        from cfgplan.live.server import LiveServer

        if isinstance(self._server, LiveServer):
            self._server.stop()


def open_live(
    address: Address,
    society: Society,
    hooks: Hooks | None,
    problem: Problem,
    config: Configuration,
    title: str,
) -> Live:
    """Serve the live page of ``society`` (running ``config`` of ``problem``,
    monitored by ``hooks``) at ``address``; a :class:`RunError` if aiohttp is
    missing or the address cannot be bound."""
    try:
        import aiohttp  # noqa: F401  (the live extra)
    except ImportError:
        raise RunError("--live needs aiohttp, which is not installed", hint=INSTALL_HINT) from None
    from cfgplan.live.model import Setup
    from cfgplan.live.server import LiveServer
    from cfgplan.live.watch import Watch

    coordinator = coordinating(hooks)
    lead = coordinator_of(problem.goal_call, config) if coordinator is None else coordinator.robot
    shown = Shown(hooks, config)  # a robot that takes over shows its coordination from then on
    setup = Setup(
        title=title,
        robots=tuple(dict.fromkeys([*config.agents, *problem.task.agents])),
        here=tuple(r.name for r in society.robots),
        coordinator=lead,
        cost=config.cost,
        started=time.time(),
    )
    watch = Watch(setup, config, problem.goal_call[1:], shown.reconfigurator)
    watch.drawing()  # the first layout loads Graphviz: now, not while the robots run
    society.subscribe(watch)
    server = LiveServer(watch, address)
    try:
        url = server.start()
    except OSError as exc:
        where = address.url().removeprefix("http://").rstrip("/")
        raise RunError(
            f"cannot serve the live page on {where}: {exc.strerror or exc}",
            hint="give another port, or 0 for any free one",
        ) from None
    print(f"live page: {url}", flush=True)
    return Live(server, url)
