"""The coordinator's side of the two-phase switch over the network (5.5, 7.3).

:class:`NetworkDeployer` runs the switch of :mod:`cfgplan.runtime.member`
with the messages of :mod:`cfgplan.runtime.protocol`:

* a robot is sent nothing of a switch before it said it is **ready**
  (:class:`~cfgplan.runtime.protocol.Ready`: its subscriber exists): its
  liveliness token appears before that subscriber is known to the others,
  and a prepare sent on the token alone was lost (a spurious "silent"
  failure and seconds lost after a restart). A robot whose token is seen
  without a ready (the coordinator started after it, or it froze and came
  back) is greeted (:class:`~cfgplan.runtime.protocol.Hello`), again after
  ``greet`` seconds, twice as long each time (at most ``greet_most``), until
  it answers;
* **prepare** to every robot of the new configuration that is alive and
  ready; each answers ``ready`` or ``refused``. A robot of the old
  configuration only that leaves (its new part is empty) has nothing to
  prepare or refuse and is not waited for — it may be the robot that froze;
* when all are ready, the coordinator installs its own part and sends
  **commit** (with the empty part, to those that leave); each robot installs
  its part between two cycles and answers ``installed``; the switch is
  *running* when every answer of the new configuration's robots is in (its
  latency is measured to that moment);
* a robot of the new configuration that is not running (no token: declared
  in the state, never started), a refusal, no answer within
  :data:`SWITCH_TIMEOUT` seconds while preparing, or a robot's liveliness
  token going away (:meth:`gone`: no waiting out the timeout for it),
  **aborts** the switch (nobody changed
  anything); the robots that failed to answer are taken as lost (in one
  decision), and the coordinator plans again without them. A commit not
  answered in time is taken as done
  (the robot installs it when it gets it, or liveliness reports it lost); a
  commit refused (the robot lost what it prepared) is sent again with the
  part, and refused again makes the robot lost: nothing is rolled back,
  the others run the new configuration;
* a message can be lost on the way: Zenoh drops one that its link's queue
  cannot take at once (as on a loaded machine), and so a robot's answer.
  The prepare or the commit is told again to the robots that have not
  answered it, ``greet`` seconds later and twice as long each time, while
  the step's wait is not over (:class:`_Telling`); a robot answers a message
  told again as it did the first time.

A robot taken as lost for its silence while liveliness still shows it alive
(a message lost, or a robot busy catching up) would otherwise never be seen
again, since its token never went away: it is tried again, as if it had come
back, :data:`RETRY` seconds later, twice as long after each silence in a row
(at most :data:`RETRY_MOST`).

A robot that says it is ready gets the running configuration's part (a
commit carrying the part; after the switch in flight, if one is). When the
task is accomplished every robot is told to **finish** (told again, as a
step of a switch is, to those that have not answered); each says so and
answers ``finished``, and the coordinator leaves
once all have answered (at most :data:`SWITCH_TIMEOUT` seconds later): a
robot that left after finishing is not lost to anyone
(:meth:`~cfgplan.runtime.Robot.release`).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

from cfgplan.reconfigure.coordinate import Done, Failed
from cfgplan.reconfigure.decision import Decision
from cfgplan.runtime.keys import configure_key
from cfgplan.runtime.member import Member, send
from cfgplan.runtime.part import Part, part_to_json
from cfgplan.runtime.protocol import (
    Abort,
    Commit,
    Duplicate,
    Finish,
    Hello,
    Phase,
    Prepare,
    State,
    ToRobot,
    new_epoch,
)
from cfgplan.runtime.zenoh_transport import ZenohTransport

__all__ = ["NOT_RUNNING", "RETRY", "RETRY_MOST", "SWITCH_TIMEOUT", "NetworkDeployer"]

NOT_RUNNING = "not running"
"""Why robots are taken as lost whose part a switch needs while no process
of theirs is seen (its token): declared in the state, never started or gone."""

SWITCH_TIMEOUT = 2.0
"""Seconds the coordinator waits for every robot to answer a step of a switch."""

RETRY = 1.0
"""Seconds after a robot alive but silent in a switch is tried again; doubled
after each silence in a row, up to :data:`RETRY_MOST`."""
RETRY_MOST = 30.0


@dataclass
class _Telling:
    """Messages to robots, told again to those that have not answered them,
    ``wait`` seconds later and twice as long each time: a message can be
    lost on the way (Zenoh drops one that its link's queue cannot take at
    once, as on a loaded machine), and a robot answers a message told again
    as it answered it the first time."""

    told: dict[str, ToRobot]  # the message each robot was told
    at: float  # when (clock) to tell again
    wait: float

    def due(self, now: float, waiting: set[str]) -> list[tuple[str, ToRobot]]:
        """What to tell again now: the messages of the robots ``waiting``."""
        if now < self.at:
            return []
        self.wait *= 2
        self.at = now + self.wait
        return [(robot, self.told[robot]) for robot in sorted(waiting & set(self.told))]


@dataclass
class _Switch:
    decision: Decision
    parts: dict[str, Part]  # those of the robots alive, which take part
    everyone: dict[str, Part]  # of every robot: what one that appears later is sent
    done: Done
    failed: Failed
    awaiting: Phase  # the answer of this step: ready (prepare), installed (commit)
    waiting: set[str]
    deadline: float
    resent: set[str] = field(default_factory=set)  # refused the commit: sent the part itself
    telling: _Telling | None = None  # the step's messages, told again to who has not answered


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
    epoch: str = field(default_factory=new_epoch)
    """This coordinator's run, on every message it sends: a robot that hears a
    new one (the coordinator started again, or another robot took over)
    follows its numbering afresh."""
    step_of: Callable[[], int] | None = None
    """The step of the sequence of goals the running configuration serves
    (on every commit: a robot that takes over goes on from it)."""
    refused: list[tuple[str, str]] = field(default_factory=list)
    """Robots that could not install a configuration the others did, with why
    (:meth:`acked`): taken as lost by the coordinator (:class:`NetworkAdaptive`)."""
    ending: tuple[set[str], float] | None = None
    """After :meth:`finish`: the robots yet to answer it, and until when (clock)."""
    _finishing: _Telling | None = None  # the finish, told again to who has not answered
    ready: set[str] = field(default_factory=set)
    """Robots that said they are ready since their token last appeared."""
    greet: float = 0.25
    """Seconds before a robot seen but not ready is greeted again (doubled each time)."""
    greet_most: float = 2.0
    _greeting: dict[str, tuple[float, float]] = field(default_factory=dict)  # when, last wait
    _owed: set[str] = field(default_factory=set)  # ready during a switch: sent their part after

    @property
    def me(self) -> str:
        return self.member.robot.name

    def _to(self, robot: str, message: ToRobot) -> None:
        send(self.transport, configure_key(self.transport.society, robot), message)

    def deploy(
        self, decision: Decision, parts: dict[str, Part], done: Done, failed: Failed
    ) -> None:
        alive = self.transport.alive
        targets = {
            r: p for r, p in parts.items() if r == self.me or (r in alive and r in self.ready)
        }
        joining = sorted(r for r in targets if r != self.me and not _empty(targets[r]))
        self.switch = _Switch(
            decision,
            targets,
            parts,
            done,
            failed,
            Phase.READY,
            set(joining),
            self.clock() + self.timeout,
        )
        own = targets.get(self.me)
        refusal = None if own is None else self.member.refusal(own)
        if refusal is not None:  # as a robot refuses a prepare
            self._abort([self.me], f"refused: {refusal}")
            return
        absent = sorted(
            r for r in parts if r != self.me and r not in alive and not _empty(parts[r])
        )
        if absent:  # its part would reach nobody: the others would wait for its data for good
            self._abort(absent, NOT_RUNNING)
            return
        told: dict[str, ToRobot] = {}
        for robot in joining:
            part = part_to_json(targets[robot])
            told[robot] = Prepare(decision.id, self.me, self.epoch, part)
            self._to(robot, told[robot])
        self.switch.telling = self._telling(told)
        if not joining:
            self._commit()

    def _commit(self) -> None:
        switch = self.switch
        assert switch is not None
        number = switch.decision.id
        others = sorted(r for r in switch.parts if r != self.me)
        joining = [r for r in others if not _empty(switch.parts[r])]
        switch.awaiting, switch.waiting = Phase.INSTALLED, set(joining)
        switch.deadline = self.clock() + self.timeout
        told: dict[str, ToRobot] = {}
        for robot in others:  # first: they install while this robot does
            leaving = None if robot in joining else part_to_json(switch.parts[robot])
            told[robot] = Commit(number, self.me, self.epoch, leaving, self.step())
            self._to(robot, told[robot])
        switch.telling = self._telling(told)
        own = switch.parts.get(self.me)
        if own is not None:
            self.member.install(number, own)
        self.parts = {**self.parts, **switch.everyone}
        self.current = number
        if not joining:
            self._finish()

    def step(self) -> int:
        return 0 if self.step_of is None else self.step_of()

    def _finish(self) -> None:
        switch, self.switch = self.switch, None
        assert switch is not None
        switch.done()
        self._pay()

    def _pay(self) -> None:
        """Send the robots that said they are ready during a switch their part."""
        owed, self._owed = self._owed, set()
        for robot in sorted(owed):
            self.resync(robot)

    def acked(self, robot: str, number: int, phase: Phase, reason: str) -> None:
        """An answer from ``robot`` to a step of switch ``number`` (``finished``:
        to :meth:`finish`)."""
        if phase == Phase.FINISHED:
            if self.ending is not None:
                self.ending[0].discard(robot)
            return
        switch = self.switch
        if switch is None or number != switch.decision.id or robot not in switch.waiting:
            return
        self._wait.pop(robot, None)  # it answers again
        if phase == Phase.REFUSED:
            if switch.awaiting is Phase.READY:
                self._abort([robot], f"refused: {reason}")
                return
            # Committed: the others install (this robot did too), nothing is
            # rolled back. It lost what it prepared (started again since?):
            # it is sent the part itself, once; refused again, it is lost.
            if robot not in switch.resent:
                switch.resent.add(robot)
                part = part_to_json(switch.parts[robot])
                commit = Commit(number, self.me, self.epoch, part, self.step())
                if switch.telling is not None:
                    switch.telling.told[robot] = commit
                self._to(robot, commit)
                return
            self.refused.append((robot, reason))
        elif phase != switch.awaiting:
            return
        switch.waiting.discard(robot)
        if not switch.waiting:
            if switch.awaiting is Phase.READY:
                self._commit()
            else:
                self._finish()

    def _abort(self, robots: list[str], reason: str) -> None:
        switch, self.switch = self.switch, None
        assert switch is not None
        for robot in sorted(r for r in switch.parts if r != self.me):
            self._to(robot, Abort(switch.decision.id, self.me, self.epoch))
        switch.failed(robots, reason)
        self._pay()

    def tick(self) -> None:
        """Give up on robots that did not answer in time; greet again those
        seen but not ready."""
        now = self.clock()
        for robot, (at, wait) in sorted(self._greeting.items()):
            if at <= now:
                self._hello(robot, min(self.greet_most, 2 * wait))
        self._tell_again(now)
        switch = self.switch
        if switch is None or now < switch.deadline:
            return
        if switch.awaiting is Phase.READY:
            for robot in switch.waiting:
                wait = min(RETRY_MOST, 2 * self._wait[robot]) if robot in self._wait else RETRY
                self._wait[robot] = wait
                self.silent[robot] = now + wait
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

    # -- who can be sent a part ----------------------------------------------

    def seen(self, robot: str) -> bool:
        """``robot``'s token appeared: whether it is ready; if not, it is greeted
        until it says it is (:meth:`said_ready`)."""
        if robot in self.ready:
            return True
        if robot not in self._greeting:
            self._hello(robot, self.greet)
        return False

    def _hello(self, robot: str, wait: float) -> None:
        self._greeting[robot] = (self.clock() + wait, wait)
        self._to(robot, Hello(self.me, self.epoch))

    def said_ready(self, robot: str) -> None:
        """``robot`` says its subscriber exists: it may be sent its part."""
        self.ready.add(robot)
        self._greeting.pop(robot, None)

    def tell(self, robot: str, state: State) -> None:
        """Send ``robot`` what the society committed (:mod:`~cfgplan.reconfigure.committed`)."""
        self._to(robot, state)

    def refuse(self, robot: str, instance: str) -> None:
        """A second process of ``robot`` (its ``instance``) stops."""
        self._to(robot, Duplicate(self.me, self.epoch, instance))

    def gone(self, robot: str) -> None:
        """``robot``'s token went away: ready no more (back, it says so again).
        A switch that awaits its answer does not wait any longer: one being
        prepared is aborted at once (the robot is lost, the coordinator plans
        without it); one committed goes on without it."""
        self.ready.discard(robot)
        self._greeting.pop(robot, None)
        self._owed.discard(robot)
        switch = self.switch
        if switch is None or robot not in switch.waiting:
            return
        if switch.awaiting is Phase.READY:
            self._abort([robot], "lost")
            return
        switch.waiting.discard(robot)
        if not switch.waiting:
            self._finish()

    def resync(self, robot: str) -> None:
        """Send ``robot`` the part it should be running (it said it is ready);
        after the switch in flight, if one is."""
        if robot == self.me:
            return
        if self.switch is not None:
            self._owed.add(robot)
            return
        part = self.parts.get(robot)
        if part is not None:
            commit = Commit(self.current, self.me, self.epoch, part_to_json(part), self.step())
            self._to(robot, commit)

    def finish(self, goal: str) -> None:
        """The task (``goal``) is accomplished: every robot ends its run; those
        alive are awaited (:meth:`ended`), and none is lost from now on."""
        self.member.robot.release()
        self._greeting.clear()
        alive = set(self.transport.alive) - {self.me}
        message = Finish(self.current, self.me, self.epoch, goal)
        for robot in sorted((set(self.parts) | alive) - {self.me}):
            self._to(robot, message)
        self.ending = (alive, self.clock() + self.timeout)
        self._finishing = self._telling(dict.fromkeys(sorted(alive), message))

    def _telling(self, told: dict[str, ToRobot]) -> _Telling:
        """``told`` (each robot's message), to be told again from ``greet``
        seconds on to those that have not answered (:class:`_Telling`)."""
        return _Telling(told, self.clock() + self.greet, self.greet)

    def _tell_again(self, now: float) -> None:
        """Tell again the step of the switch, or the finish, to the robots
        that have not answered it, while their wait is not over: without it,
        a prepare or an answer lost made the switch abort and the robot be
        taken as lost for its silence, and a finish lost left a robot
        running after the run ended."""
        switch = self.switch
        if switch is not None and switch.telling is not None and now < switch.deadline:
            for robot, message in switch.telling.due(now, switch.waiting):
                self._to(robot, message)
        if self.ending is not None and self._finishing is not None and now < self.ending[1]:
            for robot, message in self._finishing.due(now, self.ending[0]):
                self._to(robot, message)

    def ended(self) -> list[str] | None:
        """After :meth:`finish`: ``None`` while robots are still awaited, else
        those that did not answer in time (sorted; empty: every one did)."""
        if self.ending is None:
            return None
        waiting, deadline = self.ending
        if waiting and self.clock() < deadline:
            return None
        return sorted(waiting)


def _empty(part: Part) -> bool:
    """A part that only stops what the robot ran: nothing to prepare or refuse,
    so a switch does not wait for the robot (it may be the one that froze)."""
    return not part.calls and not part.channels
