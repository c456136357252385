"""The coordinator across processes: switching a society whose robots talk over Zenoh (5.5).

The robot that owns the goal (:func:`~cfgplan.reconfigure.local.coordinator_of`)
runs ``cfgplan run DOMAIN STATE --robot NAME``: it has the planner. Every
robot (itself included) runs a :class:`~cfgplan.runtime.member.Member`;
the others send it their detections. :class:`NetworkDeployer` runs the
two-phase switch of :mod:`cfgplan.runtime.member`:

* **prepare** to every robot of the new (or old) configuration that is alive;
  each answers ``ready`` or ``refused``;
* when all are ready, the coordinator installs its own part and sends
  **commit**; each robot installs its part between two cycles and answers
  ``installed``; the switch is *running* when every answer is in (its
  latency is measured to that moment);
* a refusal, or no answer within :data:`SWITCH_TIMEOUT` seconds while
  preparing, **aborts** the switch (nobody changed anything); the robots that
  failed to answer are taken as lost (in one decision), and the coordinator
  plans again without them. A commit not answered in time is taken as done
  (the robot installs it when it gets it, or liveliness reports it lost); a
  commit refused (the robot lost what it prepared) is sent again with the
  part, and refused again makes the robot lost: nothing is rolled back,
  the others run the new configuration.

A robot taken as lost for its silence while liveliness still shows it alive
(a message lost: a robot just back declares its token before its
subscribers are known everywhere; or a robot busy catching up) would
otherwise never be seen again, since its token never went away: it is
tried again, as if it had come back, :data:`RETRY` seconds later, twice as
long after each silence in a row (at most :data:`RETRY_MOST`).

A robot that appears (started late, or back after a crash) gets the running
configuration's part at once (a commit carrying the part). When the task is
accomplished every robot is told to **finish**; each says so and answers
``finished``, and the coordinator leaves once all have answered (at most
:data:`SWITCH_TIMEOUT` seconds later): a robot that left after finishing is
not lost to anyone (:meth:`~cfgplan.runtime.Robot.release`).
"""

from __future__ import annotations

import json
import secrets
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

from cfgplan.configuration.model import Configuration
from cfgplan.ir.model import Domain
from cfgplan.notation import call_text
from cfgplan.planner.task import Ground, Task
from cfgplan.reconfigure.ahead import Ahead
from cfgplan.reconfigure.coordinate import Coordinator, Done, Failed
from cfgplan.reconfigure.decision import Decision, Hysteresis
from cfgplan.reconfigure.policy import Reconfigurator
from cfgplan.runtime.events import Adaptation
from cfgplan.runtime.faults import Injection
from cfgplan.runtime.inject import Injector
from cfgplan.runtime.keys import configure_key, coordinator_key
from cfgplan.runtime.member import Member, send
from cfgplan.runtime.monitor import HOLD, Detection, Monitor
from cfgplan.runtime.part import Part, part_to_json
from cfgplan.runtime.society import Society
from cfgplan.runtime.wire import whole
from cfgplan.runtime.zenoh_transport import ZenohTransport

__all__ = [
    "RETRY",
    "RETRY_MOST",
    "SWITCH_TIMEOUT",
    "NetworkAdaptive",
    "NetworkDeployer",
    "coordinate",
]

SWITCH_TIMEOUT = 2.0
"""Seconds the coordinator waits for every robot to answer a step of a switch."""

RETRY = 1.0
"""Seconds after a robot alive but silent in a switch is tried again; doubled
after each silence in a row, up to :data:`RETRY_MOST`."""
RETRY_MOST = 30.0


@dataclass
class _Switch:
    decision: Decision
    parts: dict[str, Part]  # those of the robots alive, which take part
    everyone: dict[str, Part]  # of every robot: what one that appears later is sent
    done: Done
    failed: Failed
    phase: str  # "prepare" | "commit"
    waiting: set[str]
    deadline: float
    resent: set[str] = field(default_factory=set)  # refused the commit: sent the part itself


@dataclass
class NetworkDeployer:
    """Two-phase switches over the network (module docstring)."""

    transport: ZenohTransport
    member: Member
    timeout: float = SWITCH_TIMEOUT
    clock: Callable[[], float] = time.monotonic
    switch: _Switch | None = None
    parts: dict[str, Part] = field(default_factory=dict)  # what every robot runs now
    current: int = 0
    silent: dict[str, float] = field(default_factory=dict)
    """Robots taken as lost for not answering a prepare, with when (clock) to
    try them again should they still be alive (:meth:`due`)."""
    _wait: dict[str, float] = field(default_factory=dict)  # the last wait of each, doubled
    epoch: str = field(default_factory=lambda: secrets.token_hex(8))
    """This coordinator's run, on every message it sends: a robot that hears a
    new one (the coordinator started again) follows its numbering afresh."""
    refused: list[tuple[str, str]] = field(default_factory=list)
    """Robots that could not install a configuration the others did, with why
    (:meth:`acked`): taken as lost by the coordinator (:class:`NetworkAdaptive`)."""
    ending: tuple[set[str], float] | None = None
    """After :meth:`finish`: the robots yet to answer it, and until when (clock)."""

    @property
    def me(self) -> str:
        return self.member.robot.name

    def _to(self, robot: str, message: dict[str, object]) -> None:
        message["epoch"] = self.epoch
        send(self.transport, configure_key(self.transport.society, robot), message)

    def deploy(
        self, decision: Decision, parts: dict[str, Part], done: Done, failed: Failed
    ) -> None:
        alive = self.transport.alive
        targets = {r: p for r, p in parts.items() if r == self.me or r in alive}
        others = sorted(r for r in targets if r != self.me)
        self.switch = _Switch(
            decision,
            targets,
            parts,
            done,
            failed,
            "prepare",
            set(others),
            self.clock() + self.timeout,
        )
        own = targets.get(self.me)
        refusal = None if own is None else self.member.refusal(own)
        if refusal is not None:  # as a robot refuses a prepare
            self._abort([self.me], f"refused: {refusal}")
            return
        for robot in others:
            self._to(
                robot,
                {
                    "op": "prepare",
                    "id": decision.id,
                    "from": self.me,
                    "part": part_to_json(targets[robot]),
                },
            )
        if not others:
            self._commit()

    def _commit(self) -> None:
        switch = self.switch
        assert switch is not None
        number = switch.decision.id
        others = sorted(r for r in switch.parts if r != self.me)
        switch.phase, switch.waiting = "commit", set(others)
        switch.deadline = self.clock() + self.timeout
        for robot in others:  # first: they install while this robot does
            self._to(robot, {"op": "commit", "id": number, "from": self.me})
        own = switch.parts.get(self.me)
        if own is not None:
            self.member.install(number, own)
        self.parts = {**self.parts, **switch.everyone}
        self.current = number
        if not others:
            self._finish()

    def _finish(self) -> None:
        switch, self.switch = self.switch, None
        assert switch is not None
        switch.done()

    def acked(self, robot: str, number: int, phase: str, reason: str) -> None:
        """An answer from ``robot`` to step ``phase`` of switch ``number``
        (``finished``: to :meth:`finish`)."""
        if phase == "finished":
            if self.ending is not None:
                self.ending[0].discard(robot)
            return
        switch = self.switch
        if switch is None or number != switch.decision.id or robot not in switch.waiting:
            return
        self._wait.pop(robot, None)  # it answers again
        if phase == "refused":
            if switch.phase == "prepare":
                self._abort([robot], f"refused: {reason}")
                return
            # Committed: the others install (this robot did too), nothing is
            # rolled back. It lost what it prepared (started again since?):
            # it is sent the part itself, once; refused again, it is lost.
            if robot not in switch.resent:
                switch.resent.add(robot)
                part = part_to_json(switch.parts[robot])
                self._to(robot, {"op": "commit", "id": number, "from": self.me, "part": part})
                return
            self.refused.append((robot, reason))
        elif phase != ("ready" if switch.phase == "prepare" else "installed"):
            return
        switch.waiting.discard(robot)
        if not switch.waiting:
            if switch.phase == "prepare":
                self._commit()
            else:
                self._finish()

    def _abort(self, robots: list[str], reason: str) -> None:
        switch, self.switch = self.switch, None
        assert switch is not None
        for robot in sorted(r for r in switch.parts if r != self.me):
            self._to(robot, {"op": "abort", "id": switch.decision.id, "from": self.me})
        switch.failed(robots, reason)

    def tick(self) -> None:
        """Give up on robots that did not answer in time."""
        switch = self.switch
        if switch is None or self.clock() < switch.deadline:
            return
        if switch.phase == "prepare":
            for robot in switch.waiting:
                wait = min(RETRY_MOST, 2 * self._wait[robot]) if robot in self._wait else RETRY
                self._wait[robot] = wait
                self.silent[robot] = self.clock() + wait
            self._abort(sorted(switch.waiting), "silent")
        else:
            self._finish()

    def due(self) -> list[str]:
        """The robots taken as lost for their silence to try again now: those
        whose wait is over and that liveliness still shows alive (one that
        is not will be seen when it comes back); none while a switch is on."""
        out: list[str] = []
        if self.switch is not None:
            return out
        now, alive = self.clock(), self.transport.alive
        for robot, at in sorted(self.silent.items()):
            if robot not in alive:  # gone: back, it starts afresh
                del self.silent[robot]
                self._wait.pop(robot, None)
            elif at <= now:
                del self.silent[robot]
                out.append(robot)
        return out

    def resync(self, robot: str) -> None:
        """Send ``robot`` the part it should be running (it just appeared)."""
        part = self.parts.get(robot)
        if part is not None and robot != self.me and self.switch is None:
            self._to(
                robot,
                {"op": "commit", "id": self.current, "from": self.me, "part": part_to_json(part)},
            )

    def finish(self, goal: str) -> None:
        """The task (``goal``) is accomplished: every robot ends its run; those
        alive are awaited (:meth:`ended`), and none is lost from now on."""
        self.member.robot.release()
        alive = set(self.transport.alive) - {self.me}
        for robot in sorted((set(self.parts) | alive) - {self.me}):
            self._to(robot, {"op": "finish", "id": self.current, "from": self.me, "goal": goal})
        self.ending = (alive, self.clock() + self.timeout)

    def ended(self) -> list[str] | None:
        """After :meth:`finish`: ``None`` while robots are still awaited, else
        those that did not answer in time (sorted; empty: every one did)."""
        if self.ending is None:
            return None
        waiting, deadline = self.ending
        if waiting and self.clock() < deadline:
            return None
        return sorted(waiting)


@dataclass
class NetworkAdaptive:
    """The hooks of :func:`cfgplan.runtime.execute` on the coordinating robot."""

    coordinator: Coordinator
    deployer: NetworkDeployer
    monitor: Monitor
    injector: Injector
    _silent: list[str] | None = None  # once the finish is over: who did not answer it
    _present: set[str] = field(default_factory=set)  # robots seen (each re-synchronised once)
    reconfigures: bool = True

    def before(self, cycle: int, elapsed: float) -> None:
        self.injector(cycle, elapsed)

    def between(self, cycle: int, elapsed: float) -> None:
        for detection in self.monitor.drain():
            self.take(detection)
        self.deployer.tick()
        me = self.deployer.me
        for robot in self.deployer.due():
            detail = "alive, silent in the last switch: tried again"
            self.take(Detection("seen", me, time.time(), other=robot, how="retry", detail=detail))
        refused, self.deployer.refused = self.deployer.refused, []
        for robot, reason in refused:
            detail = f"could not install what the others did: {reason}"
            self.take(Detection("lost", me, time.time(), other=robot, how="refused", detail=detail))
        self.coordinator.tick()
        if self.coordinator.finished and self.deployer.ending is None:
            self.deployer.finish(call_text(self.coordinator.reconfigurator.goal))
        if self.deployer.ending is not None and self._silent is None:
            self._silent = self.deployer.ended()
            if self._silent is not None:  # every robot answered, or the wait is over
                goal = call_text(self.coordinator.reconfigurator.goal)
                info = (("id", self.deployer.current), ("goal", goal), ("silent", self._silent))
                self.deployer.member.robot.record(
                    Adaptation(robot=me, t=time.time(), what="finish", info=info)
                )

    def take(self, detection: Detection) -> None:
        if detection.kind == "seen" and detection.other not in self._present:
            self._present.add(detection.other)
            self.deployer.resync(detection.other)
        elif detection.kind == "lost":
            self._present.discard(detection.other)
        self.coordinator.handle(detection)

    def receive(self, payload: bytes) -> None:
        """A report or an acknowledgement sent to the coordinator."""
        try:
            message = json.loads(payload)
            if message["type"] == "ack":
                if message.get("epoch", self.deployer.epoch) != self.deployer.epoch:
                    return  # an answer to the coordinator before this one
                self.deployer.acked(
                    str(message["robot"]),
                    whole(message["id"], "a configuration id"),
                    str(message["phase"]),
                    str(message.get("reason", "")),
                )
            elif message["type"] == "report":
                self.take(Detection.read(json.dumps(message["detection"]).encode()))
        except (ValueError, KeyError, TypeError, AttributeError):
            return  # not a message of this protocol: ignored

    @property
    def finished(self) -> str | None:
        """Why the run ends, once every robot was told and answered (or the wait is over)."""
        return self.coordinator.finished if self._silent is not None else None

    @property
    def stopped(self) -> bool:
        return self.coordinator.stopped

    def close(self) -> None:
        self.coordinator.close()


def coordinate(
    society: Society,
    transport: ZenohTransport,
    task: Task,
    domain: Domain,
    goal: Ground,
    config: Configuration,
    parts: dict[str, Part],
    injections: Sequence[Injection] = (),
    *,
    hysteresis: Hysteresis | None = None,
    hold: float = HOLD,
    goals: tuple[Ground, ...] = (),
    timeout: float = SWITCH_TIMEOUT,
    kill: Callable[[str], None] | None = None,
) -> NetworkAdaptive:
    """Make the one robot of ``society`` the coordinator of its society."""
    (robot,) = society.robots
    monitor = Monitor(hold=hold)
    monitor.watch(robot)
    transport.presence_listeners.append(monitor.presence(robot.name))
    member = Member(robot, transport, monitor, forward=False)
    deployer = NetworkDeployer(transport, member, timeout, parts=dict(parts))
    reconfigurator = Reconfigurator(
        task, domain, goal, config, hysteresis or Hysteresis(), goals=goals
    )
    coordinator = Coordinator(
        reconfigurator, robot.record, robot.name, deployer, ahead=Ahead(reconfigurator)
    )
    injector = Injector(injections, society, kill=kill)
    adaptive = NetworkAdaptive(coordinator, deployer, monitor, injector)
    transport.subscribe(coordinator_key(transport.society), adaptive.receive)
    for other in sorted(_agents(task) - {robot.name}):  # ready to talk to every robot
        transport.declare(configure_key(transport.society, other))
    return adaptive


def _agents(task: Task) -> set[str]:
    """The robots and devices the state declares."""
    return {f[1] for f in task.facts if f[0] in ("robot", "device") and len(f) == 2}
