"""From detections to a running configuration again: the coordinator's loop (5.5).

A :class:`Coordinator` takes the monitor's :class:`~cfgplan.runtime.monitor.Detection` s
(from the robots of its process, or sent by the others over the network),
asks the :class:`~cfgplan.reconfigure.policy.Reconfigurator` what to run, has
a :class:`Deployer` install it on every robot, and records what happened as
trace events on its robot (``failure``, ``recovery``, ``facts``, ``switch``,
``no-configuration``, ``achieved``, ``abort``; schema in :mod:`cfgplan.runtime.schema`):

* ``failure`` / ``recovery`` of a functionality instance, and robots
  ``lost`` / ``seen``, go straight to the reconfigurator;
* a **stale** input suspects its sender, and is acted on once the
  suspicion settles (:mod:`~cfgplan.reconfigure.suspect`);
* the **latency** of a switch runs from the detection's time to the moment
  the new configuration is installed on every robot.

While a switch is being deployed (over the network that takes a round of
messages), further detections wait; in idle time the coordinator computes
the running configuration's fallbacks, one per pass.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Protocol

from cfgplan.configuration.model import Configuration
from cfgplan.notation import atom_text, call_text
from cfgplan.reconfigure.ahead import Ahead
from cfgplan.reconfigure.decision import Decision
from cfgplan.reconfigure.fallbacks import Resource
from cfgplan.reconfigure.policy import Reconfigurator
from cfgplan.reconfigure.suspect import SILENT_LINK, Blamed, Suspicions
from cfgplan.runtime.events import Adaptation
from cfgplan.runtime.monitor import HOLD, Detection
from cfgplan.runtime.part import Part

__all__ = ["Coordinator", "Deployer", "Done"]

Done = Callable[[], None]
"""Called by a :class:`Deployer` once every robot runs the new configuration."""

Failed = Callable[[list[str], str], None]
"""Called by a :class:`Deployer` when robots could not switch (refused, silent):
nobody switched; the robots named are taken as lost."""


class Deployer(Protocol):
    """Installs a decision's parts on the robots (in process, or over the network)."""

    def deploy(
        self, decision: Decision, parts: dict[str, Part], done: Done, failed: Failed
    ) -> None: ...


def cost(value: float | None) -> int | float | None:
    """A cost as the trace writes it: 44, not 44.0."""
    if value is None:
        return None
    return int(value) if float(value).is_integer() else round(value, 4)


@dataclass
class Coordinator:
    """Turns detections into switches (module docstring)."""

    reconfigurator: Reconfigurator
    record: Callable[[Adaptation], object]
    robot: str
    deployer: Deployer
    clock: Callable[[], float] = time.monotonic
    ahead: Ahead | None = None
    """Computes fallbacks on a thread; without it, :meth:`tick` computes one per call."""
    finished: str | None = None
    """Why the run should end (``achieved``), once it should."""
    stopped: bool = False
    """No admissible configuration: the society runs nothing."""
    _suspects: Suspicions = field(init=False, repr=False)  # stale inputs (suspect.py)
    _backlog: list[Detection] = field(default_factory=list)
    _deploying: bool = False
    _achieved: Configuration | None = None  # the configuration whose task was accomplished
    _installed_at: float = 0.0  # when the running configuration was deployed (time.time())
    _installed: int = -1  # its id; -1: the first, deployed before the coordinator started
    hold: float = HOLD
    """Seconds after which what was blamed only for stale outputs is tried
    again, its robot not lost; doubled with each blame of it, up to
    :data:`~cfgplan.runtime.monitor.HOLD_MAX` (the robots' hold, ``--hold``)."""
    _blamed: Blamed = field(init=False, repr=False)  # out for stale outputs (suspect.py)
    grace: float = 0.0
    """Seconds a stale link (every channel from one robot into another) is
    waited for before a computation on it is blamed
    (:attr:`~cfgplan.reconfigure.suspect.Suspicions.grace`)."""

    reported: float = 0.0
    """Seconds a stale input another robot reported is waited for at least
    (:attr:`~cfgplan.reconfigure.suspect.Suspicions.reported`)."""

    def __post_init__(self) -> None:
        self._suspects = Suspicions(self.clock, self.grace, self.robot, self.reported)
        self._blamed = Blamed(self.hold)

    @property
    def deploying(self) -> bool:
        """Whether a switch is being deployed (its detections wait)."""
        return self._deploying

    def excuse(self, robot: str, seconds: float) -> None:
        """``robot``'s process stood still: what went stale with it is not
        blamed for ``seconds`` (:meth:`~cfgplan.reconfigure.suspect.Suspicions.excuse`)."""
        self._suspects.excuse(robot, self.clock() + seconds)

    # -- input --------------------------------------------------------------

    def handle(self, detection: Detection) -> None:
        """Take one detection (queued while a switch is being deployed); none
        once the task is accomplished (robots leave then: no loss)."""
        if self.finished is not None:
            return
        if self._deploying:
            self._backlog.append(detection)
            return
        self._take(detection)
        if (
            self.ahead is not None
            and not self._deploying
            and detection.kind not in ("stale", "fresh")
        ):
            self.ahead.notify()  # after a switch: once it is deployed (no GIL contention)

    def _take(self, detection: Detection) -> None:
        kind = detection.kind
        if kind in ("stale", "fresh"):
            self._suspects.note(detection)
        elif kind in ("failure", "lost"):
            self._failure(detection)
        elif kind in ("recovery", "seen"):
            self._recovery(detection)
        elif kind == "facts":
            self._note(
                "facts",
                detection,
                added=[atom_text(f) for f in detection.added],
                removed=[atom_text(f) for f in detection.removed],
                how=detection.how,
            )
            self._apply(
                self.reconfigurator.updated(detection.added, detection.removed, "state update"),
                detection,
            )
        elif kind == "achieved":
            if not self._accomplishes(detection):
                return
            self._note(
                "achieved",
                detection,
                label=detection.label,
                functionality=call_text(detection.instance),
            )
            if not self.reconfigurator.goals:
                self.finished = "achieved"  # the last step of a sequence, or the only one
            self._apply(self.reconfigurator.achieved(), detection)

    def _accomplishes(self, detection: Detection) -> bool:
        """Whether ``detection`` is the first report that the running
        configuration's task is accomplished. A second action, or the same one
        in the next cycle, reporting it again before the switch is deployed
        must not end a step twice (and skip the next step of a sequence): a
        report made before the running configuration was deployed, or by an
        instance it does not run, is not about it. A robot's report says
        which configuration it ran (:attr:`Detection.config`); only what was
        seen here is placed by its time, on this robot's clock."""
        running = self.reconfigurator.running
        if running is None or running is self._achieved or self.finished is not None:
            return False
        if detection.config >= 0:
            if self._installed >= 0 and detection.config != self._installed:
                return False
        elif detection.t < self._installed_at:
            return False
        mine = any(
            f.label == detection.label and (f.name, *f.args) == tuple(detection.instance)
            for f in running.functionalities
        )
        if mine:
            self._achieved = running
        return mine

    def install(self, config: Configuration | None, cause: str = "install") -> None:
        """Put ``config`` on the running society with the least disruption (or
        stop it, ``None``), recorded as a ``switch`` like any other: the
        operation a sequence of configurations (7.3) is made of."""
        now = Detection("facts", self.robot, time.time(), how=cause)
        self._apply(self.reconfigurator.install(config, cause), now)
        if self.ahead is not None:
            self.ahead.notify()

    def replan(self, cause: str) -> None:
        """Plan the society afresh and install what is found (or stop it): a
        robot that takes over coordination knows no configuration running
        (:mod:`~cfgplan.reconfigure.succession`)."""
        now = Detection("facts", self.robot, time.time(), how=cause)
        self._apply(self.reconfigurator.replanned(cause), now)
        if self.ahead is not None:
            self.ahead.notify()

    def tick(self) -> None:
        """Act on settled stale suspicions; else compute a fallback (idle time)."""
        if self._deploying:
            return
        if self._backlog:
            backlog, self._backlog = self._backlog, []
            for detection in backlog:
                self.handle(detection)
            return
        if self._settled() or self._retry():
            return
        if self.ahead is None:
            self.reconfigurator.prepare()

    def close(self) -> None:
        """The run is over: the fallbacks' thread ends (after the search it
        may be in, at most :data:`~cfgplan.reconfigure.ahead.AHEAD_LIMIT`
        seconds, not waited for)."""
        if self.ahead is not None:
            self.ahead.close()

    # -- kinds --------------------------------------------------------------

    def _resource(self, detection: Detection) -> Resource | None:
        if detection.kind in ("lost", "seen"):
            return Resource("robot", robot=detection.other, text=detection.other)
        if detection.instance:
            return Resource(
                "functionality", instance=detection.instance, text=call_text(detection.instance)
            )
        return None

    def _failure(self, detection: Detection, together: tuple[Detection, ...] = ()) -> None:
        """A resource failed or a robot was lost, and with it those of
        ``together`` (robots silent in one switch): one decision for all,
        noted one by one (the facts withdrawn on the first)."""
        situation = self.reconfigurator.situation
        found: list[tuple[Detection, Resource]] = []
        for each in (detection, *together):
            resource = self._resource(each)
            if resource is None:
                continue
            if (resource.kind == "robot" and resource.robot in situation.lost) or (
                resource.kind == "functionality" and resource.instance in situation.failed
            ):
                continue  # known already
            found.append((each, resource))
        if not found:
            return
        resources = tuple(resource for _, resource in found)
        texts = " and ".join(resource.text for resource in resources)
        decision = self.reconfigurator.failed(resources[0], f"{texts} failed", resources[1:])
        withdrawn = [atom_text(f) for f in decision.withdrawn]
        for index, (each, resource) in enumerate(found):
            taken = withdrawn if index == 0 else []
            self._note_resource("failure", each, resource, detail=each.detail, withdrawn=taken)
        self._apply(decision, found[0][0])

    def _recovery(self, detection: Detection) -> None:
        """A resource works again, or a robot is seen again (5.5). A robot seen
        again is also evidence for what was blamed only because its data went
        stale (a silent robot looks, at first, like a silent computation on
        it): those instances recover with it, in one decision, so the
        configurations that need them are admissible again."""
        resource = self._resource(detection)
        if resource is None:
            return
        situation = self.reconfigurator.situation
        if (resource.kind == "robot" and resource.robot not in situation.lost) or (
            resource.kind == "functionality" and resource.instance not in situation.failed
        ):
            return  # it was never out
        together: tuple[Resource, ...] = ()
        if resource.kind == "robot":
            together = tuple(
                Resource("functionality", instance=instance, text=call_text(instance))
                for instance in self._blamed.silenced_by(resource.robot, situation)
            )
        for each in (resource, *together):
            if each.kind == "functionality":
                self._blamed.forget(each.instance)
            self._note_resource("recovery", detection, each)
        texts = " and ".join(each.text for each in (resource, *together))
        self._apply(
            self.reconfigurator.recovered(resource, f"{texts} recovered", together), detection
        )

    def _settled(self) -> bool:
        """Blame the most upstream suspect that stayed stale past its limit."""
        blamed = self._suspects.settled(self.reconfigurator.running)
        if blamed is None:
            return False
        if blamed.instance and blamed.other:
            doubling = blamed.how != SILENT_LINK
            self._blamed.blame(
                tuple(blamed.instance), blamed.other, self.clock(), doubling=doubling
            )
        self._failure(blamed)
        return True

    def _retry(self) -> bool:
        """Try again what was blamed only for stale outputs once its hold is
        over, when the robot whose data stopped is not lost (5.5, 7.2): a
        link that stalled or a robot frozen for less than its lease leaves no
        other evidence, and no scripted ``recover`` is needed. Blamed again,
        its hold doubles. True when it acted."""
        if self.finished is not None:
            return False
        due = tuple(
            Resource("functionality", instance=instance, text=call_text(instance))
            for instance in self._blamed.due(self.reconfigurator.situation, self.clock())
        )
        if not due:
            return False
        retry = Detection("recovery", self.robot, time.time(), how="retry")
        for each in due:
            self._blamed.forget(each.instance)
            self._note_resource("recovery", retry, each)
        texts = " and ".join(each.text for each in due)
        self._apply(self.reconfigurator.recovered(due[0], f"{texts} tried again", due[1:]), retry)
        return True

    # -- output -------------------------------------------------------------

    def _note(self, what: str, detection: Detection, **info: object) -> None:
        self.record(
            Adaptation(
                robot=self.robot,
                t=time.time(),
                what=what,
                info=(("detected_by", detection.robot), *info.items()),
            )
        )

    def _note_resource(
        self, what: str, detection: Detection, resource: Resource, **more: object
    ) -> None:
        """A ``failure`` or ``recovery`` of ``resource``, as ``detection`` saw it."""
        self._note(
            what,
            detection,
            resource=resource.text,
            kind=resource.kind,
            how=detection.how or detection.kind,
            **more,
        )

    def _apply(self, decision: Decision, detection: Detection) -> None:
        if decision.action == "stay":
            return
        parts = self.reconfigurator.parts(decision.previous)
        self._deploying = True
        self._suspects.clear()

        def done() -> None:
            self._deploying = False
            self._installed_at, self._installed = time.time(), decision.id
            self._report(decision, detection)
            if self.ahead is not None:
                self.ahead.notify()

        def failed(robots: list[str], reason: str) -> None:
            self._deploying = False
            self.reconfigurator.rollback(decision.previous)
            self.record(
                Adaptation(
                    robot=self.robot,
                    t=time.time(),
                    what="abort",
                    info=(("id", decision.id), ("robots", robots), ("reason", reason)),
                )
            )
            how, _, detail = reason.partition(": ")
            lost = tuple(
                Detection("lost", self.robot, detection.t, other=robot, how=how, detail=detail)
                for robot in robots
            )
            if lost:
                self._failure(lost[0], lost[1:])

        self.deployer.deploy(decision, parts, done, failed)

    def _report(self, decision: Decision, detection: Detection) -> None:
        latency = max(0.0, time.time() - detection.t)
        previous = decision.previous
        change = decision.change
        self.stopped = decision.config is None and self.finished != "achieved"
        if decision.config is None:
            if self.finished == "achieved":
                return
            self.record(
                Adaptation(
                    robot=self.robot,
                    t=time.time(),
                    what="no-configuration",
                    info=(
                        ("id", decision.id),
                        ("cause", decision.cause),
                        ("from_cost", cost(None if previous is None else previous.cost)),
                        (
                            "stopped",
                            [] if change is None else change.record()["stopped"]["functionalities"],
                        ),
                        ("why", list(decision.why)),
                        ("latency", round(latency, 6)),
                    ),
                )
            )
            return
        assert change is not None
        self.record(
            Adaptation(
                robot=self.robot,
                t=time.time(),
                what="switch",
                info=(
                    ("id", decision.id),
                    ("cause", decision.cause),
                    ("from_cost", cost(None if previous is None else previous.cost)),
                    ("to_cost", cost(decision.config.cost)),
                    ("source", decision.source),
                    ("plan_ms", round(decision.plan_seconds * 1000, 3)),
                    ("latency", round(latency, 6)),
                    *change.record().items(),
                ),
            )
        )
