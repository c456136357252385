"""Coordination taken over and handed back: the order of succession and its epochs (5.5, 7.3).

The robot that owns the goal coordinates (:func:`~cfgplan.reconfigure.local.coordinator_of`).
When it is gone — its process killed, or frozen past the lease — and the
remaining goals of the sequence name robots that are alive, one of them takes
over, so that what remains is still served:

* **the order** every robot derives from the problem alone
  (:func:`succession_of`): for the step the society is on, the robots the
  remaining goals name, each goal's own robot first. Every commit says which
  step its configuration serves (:class:`~cfgplan.runtime.protocol.Commit`),
  so every robot knows it;
* **the takeover**: the first robot of that order that is alive, once the
  coordinator's token is gone for :attr:`~cfgplan.runtime.succession.Succession.after`
  seconds, coordinates from that step on, its run one **generation** later
  (:func:`~cfgplan.runtime.protocol.new_epoch`). It knows no configuration
  running: it takes the coordinator as lost, greets every robot alive and
  plans afresh (:meth:`~cfgplan.reconfigure.coordinate.Coordinator.replan`);
* **fencing**: a robot obeys no run of a lower generation than the one it
  follows, and follows a later one only from the robot next in the order,
  once the coordinator it followed is gone
  (:meth:`~cfgplan.runtime.member.Member._fenced`). It answers a run it does
  not obey with a ``rival`` that names the run it follows;
* **convergence**: a coordinator told so by a robot — the run it follows is
  of a later generation, and its robot is alive and next in the order — steps
  down and follows it (a frozen coordinator let go, or one started again while
  its successor runs). If that robot is gone — still not alive a lease
  later: a coordinator let go reads the greeting before its session has the
  successor's token back — it counts a generation beyond it instead, and
  the robot follows it.

:class:`Steward` holds the two roles of a robot that may coordinate and
passes from one to the other.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import TYPE_CHECKING

from cfgplan.notation import atom_text, call_text
from cfgplan.reconfigure.owner import succession_of
from cfgplan.runtime.events import Adaptation
from cfgplan.runtime.member import Membership
from cfgplan.runtime.monitor import Detection
from cfgplan.runtime.part import Part

if TYPE_CHECKING:  # a robot that follows loads no planner: the coordinator's side is lazy
    from cfgplan.configuration.model import Configuration
    from cfgplan.reconfigure.coordinate import Coordinator
    from cfgplan.reconfigure.network import NetworkAdaptive
    from cfgplan.reconfigure.policy import Reconfigurator

__all__ = ["Shown", "Steward", "coordinating", "succession_of"]


TakeOver = Callable[[Membership], "NetworkAdaptive"]
"""Makes a robot that followed a coordinator its society's coordinator (its
member's step, the run it followed, one generation later)."""


class Steward:
    """The hooks of :func:`cfgplan.runtime.execute` for a robot that may
    coordinate: the coordinator's (:class:`NetworkAdaptive`) or a follower's
    (:class:`Membership`), passing from one to the other between two passes
    of the loop (module docstring)."""

    def __init__(self, role: Membership | NetworkAdaptive, take_over: TakeOver) -> None:
        self.role = role
        self._take_over = take_over

    def before(self, cycle: int, elapsed: float) -> None:
        self.role.before(cycle, elapsed)

    def between(self, cycle: int, elapsed: float) -> None:
        role = self.role
        if isinstance(role, Membership):
            if role.member.takeover_due():
                self.role = self._takeover(role)
        elif role.superseded is not None:
            leader, epoch = role.superseded
            role.retire()
            member = role.deployer.member
            member.follow(leader, epoch)
            self.role = Membership(member, role.injector)
        self.role.between(cycle, elapsed)

    def _takeover(self, following: Membership) -> NetworkAdaptive:
        """Coordinate from the step the society is on: the coordinator gone is
        lost, every robot alive is greeted, and the society planned afresh."""
        member = following.member
        gone, waited = member.leader, member.gone_for()
        adaptive = self._take_over(following)
        self.role = adaptive  # coordinating from here: what its events say is shown as such
        me, now = member.robot.name, time.time()
        reconfigurator = adaptive.coordinator.reconfigurator
        known = reconfigurator.situation  # what the society committed (committed.py)
        info = (
            ("epoch", member.epoch),
            ("after", gone),
            ("step", member.step),
            ("goal", call_text(reconfigurator.goal)),
            ("waited", round(waited, 3)),
            ("added", [atom_text(f) for f in known.asserted]),
            ("removed", [atom_text(f) for f in known.retracted]),
            ("failed", [call_text(i) for i in known.failed]),
        )
        member.robot.record(Adaptation(robot=me, t=now, what="takeover", info=info))
        detail = f"{gone}, the coordinator, is gone: {me} takes over"
        adaptive.take(Detection("lost", me, now, other=gone, how="takeover", detail=detail))
        deployer = adaptive.deployer
        deployer.parts = {r: Part(r, (), ()) for r in sorted(adaptive.members)}  # until planned
        for other in sorted((set(deployer.transport.alive) & adaptive.members) - {me, gone}):
            adaptive.take(Detection("seen", me, now, other=other, how="takeover"))
        adaptive.coordinator.replan(f"takeover from {gone}")
        if adaptive.coordinator.reconfigurator.running is None:  # nothing admissible: stop
            member.install(member.current, Part(me, (), ()))
        return adaptive

    @property
    def coordinator(self) -> Coordinator | None:
        """The coordinator while this robot coordinates."""
        if isinstance(self.role, Membership):
            return None
        from cfgplan.reconfigure.network import NetworkAdaptive  # loaded: it coordinates

        return self.role.coordinator if isinstance(self.role, NetworkAdaptive) else None

    @property
    def finished(self) -> str | None:
        return self.role.finished

    @property
    def stopped(self) -> bool:
        return self.role.stopped

    @property
    def refusal(self) -> str | None:
        return self.role.refusal

    @property
    def reconfigures(self) -> bool:
        return self.role.reconfigures

    def close(self) -> None:
        self.role.close()


def coordinating(hooks: object) -> Coordinator | None:
    """The coordinator among a run's hooks (:func:`cfgplan.reconfigure.setup.hooks`),
    if this process runs it now: what the live page, Foxglove and ROS 2 show
    the running configuration of (a :class:`Steward` that follows runs none)."""
    from cfgplan.reconfigure.local import Adaptive
    from cfgplan.reconfigure.network import NetworkAdaptive

    if isinstance(hooks, Adaptive | NetworkAdaptive | Steward):
        return hooks.coordinator
    return None


class Shown:
    """What the viewers of a run (the live page, Foxglove, the ROS 2 node) show
    of its coordination, asked anew each time: a robot that takes over
    coordinates from then on, and one that steps down no longer does."""

    def __init__(self, hooks: object, first: Configuration | None) -> None:
        self.hooks = hooks
        self._last = first

    def reconfigurator(self) -> Reconfigurator | None:
        """The reconfigurator of the coordinator this process runs now, if any."""
        coordinator = coordinating(self.hooks)
        return None if coordinator is None else coordinator.reconfigurator

    def running(self) -> Configuration | None:
        """The configuration the coordinator this process runs has running
        (``None``: nothing runs); while this process does not coordinate, the
        last one it saw (the first, on a robot that never did)."""
        reconfigurator = self.reconfigurator()
        if reconfigurator is not None:
            self._last = reconfigurator.running
        return self._last
