"""A robot's side of switching configurations across processes (5.5): the protocol's member.

The robot that owns the goal (the coordinator, which plans) switches the
society in two phases, so that every robot switches to the same
configuration and nobody runs half of two. The messages are those of
:mod:`cfgplan.runtime.protocol` (read and written only there):

0. **ready**: once its subscriber for switch messages exists, a robot says
   so (:class:`~cfgplan.runtime.protocol.Ready`), and again whenever the
   coordinator greets it (:class:`~cfgplan.runtime.protocol.Hello`): the
   coordinator sends it nothing of a switch before.
1. **prepare** (:class:`~cfgplan.runtime.protocol.Prepare`, the robot's part
   of the new configuration; an empty part for a robot that leaves it). The
   robot checks that it can run its part (every implementation is there) and
   answers ``ready`` or ``refused`` with the reason; it keeps running the old
   configuration.
2. **commit** (:class:`~cfgplan.runtime.protocol.Commit`) once every robot is
   ready: each installs its part between two of its cycles
   (:func:`~cfgplan.runtime.install.install`, keeping what both
   configurations share) and answers ``installed``. A robot that refused or
   did not answer in time makes the coordinator send **abort** instead, and
   plan again without it.

Answers are :class:`~cfgplan.runtime.protocol.Ack` s on the coordinator's key;
a robot's detections go there too
(:class:`~cfgplan.runtime.protocol.Report`), each stamped with the id of the
configuration it ran (its ``config``: a report is placed by that, not by the
robots' clocks). A commit may carry the part itself: the coordinator so
re-synchronises a robot that says it is ready (started late, or back after a
crash). **finish** ends the run when the action's task is accomplished: the
robot records a ``finish`` event (the console says the task is accomplished),
answers ``finished``, and ends its run; the coordinator leaves once every
robot has answered (or after a time limit), so that no robot takes the
others' leaving for a loss (:meth:`~cfgplan.runtime.Robot.release`).
Messages are idempotent: a repeated prepare or commit is answered again,
an old id is ignored. Every message carries the coordinator's ``epoch``,
drawn when it starts: a coordinator started again numbers its
configurations afresh, and a robot that hears a new epoch on a prepare or
commit follows it from its first id — but only if the coordinator it
followed went away since (its liveliness token): while that one is alive, a
message of another epoch is from a second coordinator, which the robot
tells it is a **rival** (:class:`~cfgplan.runtime.protocol.Rival`; it then
stops) and ignores. A robot's ``ready`` carries an ``instance`` drawn when
its process starts; a second process of the same robot name is sent
**duplicate** (:class:`~cfgplan.runtime.protocol.Duplicate`) by the
coordinator and stops (:attr:`Member.refused`). Messages come from other
processes: what cannot be read is recorded as an error and dropped.

Channels the two configurations share carry the same data either side of a
commit (the same instances at both ends, :mod:`~cfgplan.reconfigure.switch`),
so a robot that has switched and one that has not yet still understand each
other; channels of only the new configuration carry data once both ends have
switched.
"""

from __future__ import annotations

import secrets
import time
from collections.abc import Callable
from dataclasses import replace
from typing import Any, Protocol

from cfgplan.notation import call_text
from cfgplan.runtime.errors import RunError
from cfgplan.runtime.events import Adaptation, Call, Event, Lifecycle
from cfgplan.runtime.executor import Robot
from cfgplan.runtime.install import install, runnable
from cfgplan.runtime.keys import configure_key, coordinator_key
from cfgplan.runtime.launch import REFUSED
from cfgplan.runtime.monitor import HOLD, Monitor
from cfgplan.runtime.part import Part, part_from_json
from cfgplan.runtime.protocol import (
    Abort,
    Ack,
    CallError,
    Commit,
    Duplicate,
    Finish,
    Hello,
    Phase,
    Prepare,
    ProtocolError,
    Ready,
    Report,
    Rival,
    State,
    ToCoordinator,
    ToRobot,
    encode,
    generation,
    read_to_robot,
)
from cfgplan.runtime.succession import Succession, candidates
from cfgplan.security.rates import Throttle

__all__ = ["Member", "Membership", "Network", "send"]


class Network(Protocol):
    """What the protocol needs of a transport (the Zenoh one has it)."""

    society: str

    def subscribe(self, key: str, handler: Any) -> None: ...

    def publish(self, key: str, payload: bytes) -> None: ...


def send(network: Network, key: str, message: ToRobot | ToCoordinator) -> None:
    """Publish one message of :mod:`cfgplan.runtime.protocol` on ``key``."""
    network.publish(key, encode(message))


class Member:
    """Answers the coordinator for ``robot`` and forwards its detections.

    ``forward``: the robot follows a coordinator over the network (it says it
    is ready and sends its detections); False on the coordinator itself, which
    reads its monitor and needs no part sent."""

    def __init__(
        self,
        robot: Robot,
        network: Network,
        monitor: Monitor | None = None,
        *,
        forward: bool = True,
        without: str = "stop",
        hold: float = HOLD,
        succession: Succession | None = None,
        leader: str = "",
    ) -> None:
        self.robot = robot
        self.succession = succession
        """The order of succession (a robot that runs the problem knows it):
        this robot takes over coordination when it is next
        (:meth:`takeover_due`), and follows a later run only from the robot
        that is next; ``None``: the access control alone says who may."""
        self.step = 0  # the step of the sequence the configuration it runs serves
        self.known: State | None = None
        """The last :class:`~cfgplan.runtime.protocol.State` of the run it
        follows: what the society committed on top of the state it was
        started with (a robot that takes over plans from it)."""
        self._lost_at: float | None = None  # when the leader's token went (monotonic)
        self.without = without
        """What this robot does once its coordinator is gone for ``hold``
        seconds (``--without-coordinator``): ``stop`` its part, or ``run`` on."""
        self.hold = hold
        self._gone: float | None = None  # when the coordinator followed went (monotonic)
        self.orphaned = False
        """True while its part is stopped because its coordinator is gone."""
        self.network = network
        self.monitor = monitor
        self.forward = forward
        self.current = 0  # the configuration id it runs
        self.epoch = ""  # the coordinator's run it follows (``epoch`` of its messages)
        self.leader = leader
        """The robot that coordinates that run; before any message of it, the
        robot expected to (the goal's, for a robot that runs the problem): its
        token going then is a coordinator lost before first contact."""
        self._leader_gone = False  # its token went since: a new epoch may be followed
        self._rivals: set[str] = set()  # epochs of second coordinators told (a few)
        self._listening = False  # to the presence of the others and to its robot's calls
        self.on_later: Callable[[str, str], None] | None = None
        """While this robot coordinates: told of a message of a later run
        (its sender and epoch), which may have taken over from it."""
        self.instance: str = getattr(network, "instance", None) or secrets.token_hex(8)
        """This process, in its ``ready`` (and its process token over Zenoh)."""
        self.refused: str | None = None
        """Why this process may not run its robot (another one does): the run ends."""
        self.pending: dict[int, Part] = {}
        self.finished: str | None = None
        self._erring: set[str] = set()  # labels whose last call failed (already told)
        self._errors: list[CallError] = []  # to send between cycles
        self._throttle = Throttle()  # what is said of unreadable switch messages
        network.subscribe(configure_key(network.society, robot.name), self.receive)
        declare = getattr(network, "declare", None)
        if declare is not None:  # the first answer then goes out at once
            declare(coordinator_key(network.society, robot.name))
        notices = getattr(network, "notices", None)
        if notices is not None:  # a flood's drops, once per interval (cfgplan.security.rates)
            notices.append(self.error)
        if hasattr(network, "conflict_handled"):  # another problem in the society: see conflict
            network.conflict_handled = True
        if forward:  # the subscriber exists: the coordinator may send a part now
            self._send(Ready(robot.name, self.instance))
            self._listen()

    def _listen(self) -> None:
        """Follow the others' presence and this robot's calls (once)."""
        if self._listening:
            return
        self._listening = True
        self.robot.subscribe(self._event)
        listeners = getattr(self.network, "presence_listeners", None)
        if listeners is not None:
            listeners.append(self._presence)

    def lead(self, epoch: str) -> None:
        """This robot coordinates the run ``epoch`` from now on: it sends no
        reports and fences off every other run (:meth:`_fenced`)."""
        self.forward = False
        self.epoch, self.leader, self._leader_gone = epoch, self.robot.name, False
        self.pending, self._lost_at, self._gone = {}, None, None

    def follow(self, leader: str, epoch: str) -> None:
        """This robot, which coordinated, follows ``leader``'s run ``epoch``
        from now on (a later generation took over while it stood still): it
        says it is ready, and ``leader`` sends it its part."""
        self.forward = True
        self.epoch, self.leader, self._leader_gone = epoch, leader, False
        self.current, self.pending = 0, {}
        self._listen()
        self._watch_leader()
        self._send(Ready(self.robot.name, self.instance))

    def _watch_leader(self) -> None:
        """Watch the coordinator followed, where only some robots are watched
        (:meth:`~cfgplan.runtime.zenoh_transport.ZenohTransport.narrow`)."""
        watch = getattr(self.network, "watch_robot", None)
        if watch is not None:
            watch(self.leader)

    def takeover_due(self) -> bool:
        """Whether this robot takes over coordination now: the coordinator it
        followed is gone for :attr:`Succession.after` seconds or more, and
        this robot is the first of the order of succession still alive."""
        if self.succession is None or not self.forward or self._lost_at is None:
            return False
        if self.finished is not None or self.refused is not None:
            return False
        if time.monotonic() - self._lost_at < self.succession.after:
            return False
        return self._next(self.leader) == self.robot.name

    def gone_for(self) -> float:
        """Seconds since the coordinator followed went (0 if it did not)."""
        return 0.0 if self._lost_at is None else time.monotonic() - self._lost_at

    def _next(self, gone: str) -> str | None:
        """Who takes over from ``gone`` as this robot sees the society."""
        assert self.succession is not None
        able = candidates(self.network, self.robot.name)
        return self.succession.successor(self.step, able, gone)

    def _presence(self, other: str, alive: bool) -> None:
        """The coordinator followed went away (a message of its run, after it
        is seen again, says it is the same run: :meth:`receive`), or came
        back: a robot that stopped its part without it says it is ready
        again, so that it is sent its part (a coordinator whose own stall
        hid the loss would not send it)."""
        if other != self.leader:
            return
        if not alive:
            self._leader_gone = True
            self._gone = self._lost_at = time.monotonic()
            return
        self._gone = self._lost_at = None
        if self.orphaned:
            self._send(Ready(self.robot.name, self.instance))

    def _alone(self) -> None:
        """The coordinator followed is gone for longer than the hold: with
        ``without`` = ``stop``, this robot stops its part (every stop hook is
        called: an action halts its motors) and runs empty, watching, until a
        coordinator sends it a part again — as Nav2's bond stops a robot whose
        supervisor went silent; with ``run``, it runs on. Said either way."""
        if self._gone is None or self.finished is not None or self.orphaned:
            return
        gone = time.monotonic() - self._gone
        if gone < self.hold:
            return
        self._gone = None
        if self.without != "stop":
            self.error(
                f"{self.leader}, the coordinator, is gone for {gone:.1f} s: {self.robot.name} "
                "runs on (--without-coordinator run)"
            )
            return
        self.install(self.current, Part(self.robot.name, (), ()))
        self.orphaned = True
        self.error(
            f"{self.leader}, the coordinator, is gone for {gone:.1f} s: {self.robot.name} "
            "stops its part (--without-coordinator stop) until a coordinator sends it one"
        )

    def _event(self, event: Event) -> None:
        """Note the first failed call of each run of them (:meth:`report` sends it)."""
        if not isinstance(event, Call):
            return
        if event.status == "ran":
            self._erring.discard(event.label)
        # a resource's failure (``failure``) goes as a detection, with its message
        failed = event.status in ("error", "timeout") and not event.failure
        if failed and event.label not in self._erring:
            self._erring.add(event.label)
            what = f"{event.label}: {call_text(event.instance)}"
            self._errors.append(CallError(self.robot.name, what, event.error))

    def receive(self, payload: bytes) -> None:
        """One message from the coordinator (on the robot's thread, between cycles)."""
        try:
            message = read_to_robot(payload)
        except ProtocolError as exc:
            if self._throttle.note(exc.kind, time.monotonic()):  # a flood: once a second
                self.error(f"a switch message that cannot be read: {exc}")
            return
        if isinstance(message, Duplicate):
            if message.instance == self.instance and self.refused is None:
                self.refused = (
                    f"another process runs robot {self.robot.name} in society "
                    f"{self.network.society} (the coordinator, {message.sender}, keeps it): "
                    "this one stops"
                )
            return
        epoch = message.epoch
        if epoch == self.epoch:
            if self._alive(message.sender):  # it did not go, or came back as it was
                self._leader_gone = False
        elif self._fenced(message):
            return
        if isinstance(message, Hello):
            self._send(Ready(self.robot.name, self.instance))
            return
        if epoch != self.epoch and isinstance(message, Prepare | Commit | State):
            # A coordinator started again (or one that took over): it numbers
            # its configurations afresh, and this robot keeps running its part
            # until that coordinator installs one.
            self.epoch, self.current, self.pending = epoch, 0, {}
            self._lead_by(message.sender)
        elif epoch != self.epoch and isinstance(message, Abort):
            return  # of a switch of a coordinator no longer followed
        if isinstance(message, State):
            if self.known is None or self.known.epoch != epoch or message.id >= self.known.id:
                self.known, self.step = message, message.step
        elif isinstance(message, Prepare):
            self._prepare(message.id, message.part)
        elif isinstance(message, Commit):
            self._commit(message.id, message.part, message.step)
        elif isinstance(message, Abort):
            self.pending.pop(message.id, None)
        else:
            self._finish(message)

    def _alive(self, robot: str) -> bool:
        """Whether ``robot``'s token is up as the network sees it now (ahead of
        the presence changes this robot has taken: a message of a robot may
        wait in the queue while its token goes)."""
        return robot in getattr(self.network, "alive", (robot,))

    def _lead_by(self, sender: str) -> None:
        """Follow ``sender``'s run from now on. Alive, it is a coordinator again:
        no hold runs out, nobody takes over. Gone already — its message waited
        in the queue while its token went — it is lost as if its token went
        now (unless it was lost before): a takeover is not missed."""
        self.leader = sender
        self._watch_leader()
        if self._alive(sender):
            self._leader_gone, self._lost_at, self._gone = False, None, None
            return
        self._leader_gone = True
        if self._lost_at is None:
            self._lost_at = self._gone = time.monotonic()

    def _fenced(self, message: ToRobot) -> bool:
        """Whether ``message``, of another epoch than the one followed, is not
        obeyed: it is of a lower generation (fenced off: a run that was taken
        over), or the coordinator followed has not gone since (a second
        coordinator), or it is of a later generation from a robot that is
        not next in the order of succession. Not fenced: a run of the same
        generation (the coordinator started again) or of a later one from
        the robot next in the order, once the one followed went. The first
        time, the sender is told (:class:`~cfgplan.runtime.protocol.Rival`,
        with the run followed: it stops, or steps down) and the console
        says so."""
        if not self.epoch or isinstance(message, Duplicate):
            return False
        mine, theirs = generation(self.epoch), generation(message.epoch)
        if self._leader_gone and theirs == mine:
            return False
        if not self.forward and theirs > mine and self.on_later is not None:
            self.on_later(message.sender, message.epoch)  # a successor? (the coordinator decides)
            return True
        if theirs > mine and message.sender == self.leader and not self._leader_gone:
            return False  # the coordinator followed counts a later generation (told of one)
        claimed = self.succession is None or self._next(self.leader) == message.sender
        if self._leader_gone and theirs > mine and claimed:
            return False
        if message.epoch not in self._rivals and len(self._rivals) < 16:
            self._rivals.add(message.epoch)
            self._send(Rival(self.robot.name, message.epoch, self.leader, self.epoch))
            older = " (an older run, fenced off)" if theirs < mine else ""
            self.error(
                f"a second coordinator ({message.sender}){older} of society "
                f"{self.network.society} is ignored: {self.leader} coordinates it"
            )
        return True

    def _finish(self, message: Finish) -> None:
        """The coordinator says the task is accomplished: say so, answer, end the run."""
        if self.finished is None:
            self.finished = "achieved"
            self.robot.release()
            info: list[tuple[str, object]] = [("id", message.id), ("from", message.sender)]
            if message.goal:
                info.append(("goal", message.goal))
            self.robot.record(
                Adaptation(robot=self.robot.name, t=time.time(), what="finish", info=tuple(info))
            )
        self._ack(message.id, Phase.FINISHED, epoch=message.epoch)  # whoever said it

    def refusal(self, part: Part) -> str | None:
        """Why this robot cannot run ``part`` (:func:`~cfgplan.runtime.install.runnable`),
        or None: the check a prepare makes, for the coordinator's own part."""
        try:
            runnable(self.robot, part)
        except (ValueError, RunError) as exc:
            return str(exc)
        return None

    def _part(self, data: object) -> Part:
        part = part_from_json(data)
        runnable(self.robot, part)
        return part

    def _prepare(self, number: int, data: object) -> None:
        if number in self.pending:  # a repeated prepare
            self._ack(number, Phase.READY)
            return
        if number <= self.current:
            return  # a switch older than the configuration it runs: ignored
        try:
            part = self._part(data)
        except (ValueError, RunError) as exc:
            self._ack(number, Phase.REFUSED, str(exc))
            return
        self.pending[number] = part
        self._ack(number, Phase.READY)

    def _commit(self, number: int, data: object, step: int = 0) -> None:
        if number >= self.current:
            self.step = step  # the sequence's step (a successor goes on from it)
        if number == self.current and data is None:
            self._ack(number, Phase.INSTALLED)  # a repeated commit
            return
        if number < self.current:
            return
        try:
            part = self.pending.pop(number) if data is None else self._part(data)
        except KeyError:
            reason = f"configuration {number} was never prepared here"
            self._ack(number, Phase.REFUSED, reason)
            return
        except (ValueError, RunError) as exc:
            self._ack(number, Phase.REFUSED, str(exc))
            return
        self.install(number, part)
        self._ack(number, Phase.INSTALLED)

    def install(self, number: int, part: Part) -> None:
        """Run ``part`` as configuration ``number`` from the next cycle on."""
        self.orphaned = False
        installed = install(self.robot, part)
        same = number == self.current and not installed.changed  # a re-synchronisation
        self.current = number
        self.pending = {k: v for k, v in self.pending.items() if k > number}
        if same:
            return
        # whose switch it obeyed (the live page follows its leader)
        run = (("epoch", self.epoch), ("leader", self.leader)) if self.epoch else ()
        self.robot.record(
            Adaptation(
                robot=self.robot.name,
                t=time.time(),
                what="install",
                info=(("id", number), *installed.record(), *run),
            )
        )

    def _send(self, message: ToCoordinator) -> None:
        send(self.network, coordinator_key(self.network.society, self.robot.name), message)

    def _ack(self, number: int, phase: Phase, reason: str = "", epoch: str | None = None) -> None:
        epoch = self.epoch if epoch is None else epoch
        self._send(Ack(self.robot.name, number, phase, epoch, reason))

    @property
    def conflict(self) -> str | None:
        """Why this robot stops because a robot of its society runs another
        problem (:mod:`cfgplan.security.identity`), or ``None``."""
        return getattr(self.network, "conflict", None)

    def report(self) -> None:
        """Send the coordinator the calls that failed and the detections of
        this robot's monitor; note a robot of another problem (:attr:`conflict`)."""
        if self.refused is None and self.conflict is not None:
            self.refused = self.conflict
        for _, count in self._throttle.due(time.monotonic()):
            self.error(f"{count} more switch message(s) that cannot be read in the last second")
        errors, self._errors = self._errors, []
        for error in errors:
            self._send(error)
        if self.forward:
            self._alone()
        if self.monitor is None or not self.forward:
            return
        for detection in self.monitor.drain():
            made_under = replace(detection, config=self.current)  # the cycle just run's
            self._send(Report(self.robot.name, made_under))

    def error(self, message: str, channel: str | None = None) -> None:
        """Record a message that was dropped (an ``error`` event: the console
        says it), with the channel it came on if any."""
        info: tuple[tuple[str, object], ...] = (("message", message),)
        if channel is not None:
            info += (("channel", channel),)
        self.robot.record(Lifecycle(robot=self.robot.name, t=time.time(), what="error", info=info))


class Membership:
    """The hooks of :func:`cfgplan.runtime.execute` for a robot that follows a
    coordinator: scripted faults before each cycle, detections sent after."""

    def __init__(self, member: Member, before: Any = None) -> None:
        self.member = member
        self.injector = before
        """What applies the scripted faults before each cycle (or None)."""
        self.stopped = False
        self.reconfigures = True

    def before(self, cycle: int, elapsed: float) -> None:
        if self.injector is not None:
            self.injector(cycle, elapsed)

    def between(self, cycle: int, elapsed: float) -> None:
        self.member.report()

    def close(self) -> None:
        """Nothing runs beside the loop."""

    @property
    def finished(self) -> str | None:
        return REFUSED if self.member.refused is not None else self.member.finished

    @property
    def refusal(self) -> str | None:
        return self.member.refused
