"""What the robots' thread hands the live page's server, and what it reads back.

A :class:`Watch` is subscribed to the society (``Society.subscribe``): each
event updates its :class:`~cfgplan.live.model.Page` under a lock, in a few
dictionary updates, so the robots' cycles are not slowed. The server's
thread reads, under the same lock, the page's state and new timeline entries,
and, from the coordinator's :class:`~cfgplan.reconfigure.policy.Reconfigurator`
(while this process runs the coordinator: from the start, or once its robot
took over), the running configuration and its fallbacks computed ahead of
time (5.5, 7.2) — it never plans, and nothing it reads changes the society.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Sequence
from typing import Any

from cfgplan.configuration.model import Configuration
from cfgplan.live.diagram import drawing
from cfgplan.live.model import Limits, Page, Setup
from cfgplan.notation import call_text
from cfgplan.reconfigure.coordinate import cost
from cfgplan.reconfigure.fallbacks import resources
from cfgplan.reconfigure.policy import Reconfigurator
from cfgplan.reconfigure.switch import change
from cfgplan.runtime.events import Event

__all__ = ["Watch", "fallback_rows"]


def fallback_rows(reconfigurator: Reconfigurator) -> list[dict[str, Any]]:
    """For each resource of the running configuration: whether its fallback
    is computed yet, its cost (``None``: nothing admissible), its robots and
    what it would stop and start."""
    running, situation = reconfigurator.running, reconfigurator.situation
    if running is None:
        return []
    rows = []
    for resource in resources(running, reconfigurator.task.media):
        # read-only: the fallbacks the coordinator keeps (Reconfigurator.fallback takes its lock)
        known, config = reconfigurator.fallback(situation, resource)
        row: dict[str, Any] = {"resource": resource.text, "kind": resource.kind, "known": known}
        if config is not None:
            moved = change(running, config)
            row.update(
                cost=cost(config.cost),
                robots=config.robots,
                stopped=[call_text(f.key) for f in moved.stopped],
                started=[call_text(f.key) for f in moved.started],
            )
        else:
            row.update(cost=None, robots=[], stopped=[], started=[])
        rows.append(row)
    return rows


class Watch:
    """The live page's view of a run (module docstring)."""

    def __init__(
        self,
        setup: Setup,
        config: Configuration,
        first: Sequence[str] = (),
        reconfigurator: Reconfigurator | Callable[[], Reconfigurator | None] | None = None,
        limits: Limits | None = None,
    ) -> None:
        self.first = tuple(first)
        self._source = reconfigurator
        """The coordinator's reconfigurator, or what says which it is now
        (``None`` while this process does not coordinate)."""
        self._page = Page(setup, limits or Limits())
        self._lock = threading.Lock()
        self._config: Configuration | None = config
        self._drawn = 1  # the number of the drawing of _config
        self._drawing: tuple[int, str, str | None] | None = None
        self._draw_lock = threading.Lock()  # one layout at a time
        self._config_lock = threading.Lock()  # _config and _drawn

    @property
    def reconfigurator(self) -> Reconfigurator | None:
        """The reconfigurator of the coordinator this process runs now, if any."""
        source = self._source
        return source() if callable(source) else source

    def __call__(self, event: Event) -> None:
        """A robot's event (the robots' thread): update the page."""
        with self._lock:
            self._page.apply(event)

    def state(self) -> dict[str, Any]:
        """The page's state (the server's thread), with the drawing's number
        and the fallbacks."""
        with self._lock:
            out = self._page.state()
        drawn = self._running()
        out["drawing"] = drawn
        r = self.reconfigurator
        if r is None:
            out["fallbacks"] = None
            out["fallbacks_note"] = (
                f"computed on the coordinator, {out['coordinator']}: open its page to see them"
                if not out["decides"]
                else "not computed: the run does not reconfigure (--no-reconfigure)"
            )
        elif r.goals:
            out["fallbacks"] = None
            out["fallbacks_note"] = "not computed ahead in a sequence of configurations (7.3)"
        else:
            out["fallbacks"] = fallback_rows(r)
            out["fallbacks_note"] = ""
        return out

    def entries(self, after: int) -> list[dict[str, Any]]:
        """Timeline entries numbered above ``after``."""
        with self._lock:
            return self._page.entries(after)

    @property
    def seq(self) -> int:
        with self._lock:
            return self._page.seq

    def _running(self) -> int:
        """The number of the running configuration's drawing (0: none runs)."""
        r = self.reconfigurator
        with self._config_lock:
            if r is not None and r.running is not self._config:
                self._config = r.running
                self._drawn += 1
            return self._drawn if self._config is not None else 0

    def drawing(self) -> tuple[int, str, str | None]:
        """The running configuration's number, DOT source and tagged SVG
        (laid out once per configuration; ``""``: none runs)."""
        with self._draw_lock:
            return self._draw()

    def _draw(self) -> tuple[int, str, str | None]:
        number = self._running()
        cached = self._drawing
        if cached is not None and cached[0] == number:
            return cached
        with self._config_lock:
            config = self._config
        if config is None:
            made: tuple[int, str, str | None] = (number, "", None)
        else:
            source, svg = drawing(config, self.first)
            made = (number, source, svg)
        self._drawing = made
        return made
