"""The coordinator across processes: switching a society whose robots talk over Zenoh (5.5).

The robot that owns the goal (:func:`~cfgplan.reconfigure.local.coordinator_of`)
runs ``cfgplan run DOMAIN STATE --robot NAME``: it has the planner. Every
robot (itself included) runs a :class:`~cfgplan.runtime.member.Member`;
the others send it their detections, their answers and their word that they
are ready (:mod:`cfgplan.runtime.protocol`). :class:`NetworkAdaptive` reads
them and drives the :class:`~cfgplan.reconfigure.deployer.NetworkDeployer`,
which runs the two-phase switch (the rules are told there).

A robot that appears is taken back (a ``seen`` detection for the
coordinator) only once it said it is ready: it is then sent its part at once,
and any switch it takes part in reaches it. A helper's functionality that fails a call
(its implementation raised) is recorded here as an ``error`` event with the
helper's own message, so the coordinator's console says why, not only that
its input went stale. A message that cannot be read is recorded as an
``error`` event and dropped.

No split brain: a second process of a robot that is alive (its ``ready``
carries another ``instance`` than the first one's) is told it is a
:class:`~cfgplan.runtime.protocol.Duplicate` and stops; a coordinator told by
a robot that it is a :class:`~cfgplan.runtime.protocol.Rival` (the robot
follows another coordinator, alive) stops (:attr:`NetworkAdaptive.refusal`).
Each robot speaks on a key of its own (:func:`~cfgplan.runtime.keys.coordinator_key`),
one for each robot and device of the state: nobody else is heard, and a
message that says it is from another robot than its key's is dropped (the
first few said).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

from cfgplan.configuration.model import Configuration
from cfgplan.ir.model import Domain
from cfgplan.notation import call_text
from cfgplan.planner.task import Ground, Task
from cfgplan.reconfigure.ahead import Ahead
from cfgplan.reconfigure.committed import state_of
from cfgplan.reconfigure.coordinate import Coordinator
from cfgplan.reconfigure.decision import Hysteresis
from cfgplan.reconfigure.deployer import RETRY, RETRY_MOST, SWITCH_TIMEOUT, NetworkDeployer
from cfgplan.reconfigure.owner import coordinators_of
from cfgplan.reconfigure.policy import Reconfigurator
from cfgplan.reconfigure.situation import Situation
from cfgplan.reconfigure.stall import Doubts, Heartbeat
from cfgplan.reconfigure.trust import beyond_its_own
from cfgplan.runtime.errors import printable
from cfgplan.runtime.events import Adaptation
from cfgplan.runtime.faults import Injection
from cfgplan.runtime.inject import Injector
from cfgplan.runtime.keys import configure_key, coordinator_key
from cfgplan.runtime.launch import REFUSED
from cfgplan.runtime.member import Member
from cfgplan.runtime.monitor import HOLD, Detection, Monitor
from cfgplan.runtime.part import Part
from cfgplan.runtime.protocol import (
    MAX_GENERATION,
    Ack,
    CallError,
    ProtocolError,
    Ready,
    Report,
    Rival,
    State,
    generation,
    new_epoch,
    read_to_coordinator,
)
from cfgplan.runtime.society import Society
from cfgplan.runtime.succession import Succession, candidates
from cfgplan.runtime.zenoh_transport import DEFAULT_LEASE, ZenohTransport
from cfgplan.security.rates import Throttle

__all__ = [
    "RETRY",
    "RETRY_MOST",
    "SWITCH_TIMEOUT",
    "NetworkAdaptive",
    "NetworkDeployer",
    "coordinate",
    "coordinators_of",
]


@dataclass
class NetworkAdaptive:
    """The hooks of :func:`cfgplan.runtime.execute` on the coordinating robot."""

    coordinator: Coordinator
    deployer: NetworkDeployer
    monitor: Monitor
    injector: Injector
    _silent: list[str] | None = None  # once the finish is over: who did not answer it
    _present: set[str] = field(default_factory=set)  # robots seen (each re-synchronised once)
    _held: dict[str, Detection] = field(default_factory=dict)  # seen, not yet ready
    _instances: dict[str, str] = field(default_factory=dict)  # the process of each robot
    _processes: dict[str, set[str]] = field(default_factory=dict)  # each robot's live ones
    _noted: set[str] = field(default_factory=set)  # strangers and rivals said (a few)
    refusal: str | None = None
    """Why this coordinator stops: another one coordinates the society."""
    _dropped: int = 0  # messages the transport dropped, said so far
    members: frozenset[str] = frozenset()  # the state's robots (coordinate()): whose processes
    heartbeat: Heartbeat | None = None  # tells this process's own stalls (coordinate())
    doubts: Doubts | None = None  # the losses held after such a stall
    reconfigures: bool = True
    _throttle: Throttle = field(default_factory=Throttle)  # what is said of dropped messages
    _twins: set[str] = field(default_factory=set)  # other processes of this robot, alive
    _rivals: dict[str, tuple[Rival, float]] = field(default_factory=dict)  # said, by robot
    _claims: dict[str, tuple[str, str, float]] = field(default_factory=dict)
    """Later runs said, by robot, whose leader was not alive here then: the
    leader, its run, and until when (the deployer's clock) that is weighed
    (:meth:`_weigh_claims`)."""
    _ended: dict[str, tuple[str, float]] = field(default_factory=dict)  # process gone, name up
    _hidden: set[str] = field(default_factory=set)  # lost while a session held their name
    _presence: Callable[[str, bool], None] | None = None  # the monitor's listener
    process_grace: float = 0.5
    """Seconds a robot's name may stay alive after its process ended (its two
    tokens go one after the other) before the name is taken as held by
    another session."""
    coordinators: frozenset[str] = frozenset()
    """The robots that may coordinate (coordinate(): with keys, those the
    society's keys mark so; without, the state's robots)."""
    succession: Succession | None = None
    """The order of succession (:mod:`cfgplan.runtime.succession`): who may
    have taken over from this coordinator while it stood still."""
    superseded: tuple[str, str] | None = None
    """The coordinator, and its run, this one steps down for (a later
    generation took over while this one stood still): it follows it now."""
    retired: bool = False  # stepped down: what reaches it is no longer read
    _shared: tuple[object, ...] = ()  # what the last State said (situation, step, id, epoch)
    _state: State | None = None  # that State (None: too large to send)
    _told: set[str] = field(default_factory=set)  # the robots sent it
    _cut_off: bool = False  # its own link to its router is lost (said once per cut)

    def before(self, cycle: int, elapsed: float) -> None:
        self.injector(cycle, elapsed)

    def between(self, cycle: int, elapsed: float) -> None:
        conflict = getattr(self.deployer.transport, "conflict", None)
        if self.refusal is None and conflict is not None:
            self.refusal = conflict  # a robot of another problem in the society: this one stops
        dropped = self.deployer.transport.dropped
        if dropped > self._dropped:
            most = self.deployer.transport.options.backlog
            self.deployer.member.error(
                f"messages to the coordinator dropped: {dropped - self._dropped} more than "
                f"the {most} that may wait (a robot floods it)"
            )
            self._dropped = dropped
        self._say_counts()
        if self._ended:
            self._settle_ended()
        if self._rivals and self.refusal is None:
            self._weigh_rivals()
        if self._claims:
            self._weigh_claims()
        detections = self.monitor.drain()
        self._stalled()  # after the drain: a stall before any loss drained is seen
        self._cut_from_router()
        for detection in detections:
            if not self._doubt(detection):
                self.take(detection)
        self._settle_doubts()
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
        self._share()
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

    def _share(self) -> None:
        """Once nothing is in flight, tell every robot that is ready what the
        society committed — the situation on top of the state, and the step —
        each time it changed, and each robot that is ready anew
        (:mod:`~cfgplan.reconfigure.committed`): a robot that takes over plans
        from it."""
        deployer = self.deployer
        if deployer.switch is not None or self.coordinator.deploying or deployer.ending:
            return
        situation = self.coordinator.reconfigurator.situation
        step = deployer.step()
        now = (situation, step, deployer.current, deployer.epoch)
        if now != self._shared:
            self._shared, self._told = now, set()
            self._state = state_of(situation, deployer.current, deployer.me, deployer.epoch, step)
            if self._state is None:
                self._once(
                    "situation too large",
                    "the situation is too large to tell the robots (a robot that takes over "
                    "plans from the state it was started with)",
                )
        if self._state is None:
            return
        for robot in sorted(deployer.ready - self._told - {deployer.me}):
            deployer.tell(robot, self._state)
            self._told.add(robot)

    def _stalled(self) -> None:
        """Whether this process stood still for half the lease or more since the last
        pass (:mod:`cfgplan.reconfigure.stall`): then its session stood still
        too and may see robots lost that never stopped. That is said,
        losses seen in the next two leases are held, and what went stale with
        this robot is not blamed in them (its outputs and its inputs stopped
        because it stood still; :meth:`Coordinator.excuse`)."""
        if self.heartbeat is None or self.doubts is None:
            return
        pause, lease = self.heartbeat.take(), self.doubts.lease
        if pause > self.doubts.threshold:
            self.doubts.stalled(time.monotonic())
            self.coordinator.excuse(self.deployer.me, 2 * lease)
            self.deployer.member.error(
                f"{self.deployer.me}'s process stood still for {pause:.1f} s, half the lease "
                f"or more (the lease is {lease:g} s); robots seen lost now are "
                "checked again before anything is withdrawn"
            )

    def _cut_from_router(self) -> None:
        """Whether this robot, a client of a router, lost its own link to it
        since the last pass, or has none (:meth:`ZenohTransport.router_link_lost`):
        then every robot it watched went at once in its own session, whether
        it stopped or not. A router that stopped reading the links of healthy
        clients past the lease (while another client's lossy link held it
        up) drops them all, and they connect again when it reads again.
        Losses seen then are held, as after this process's own stall
        (:meth:`_stalled`), for as long as the cut lasts and two leases more
        (:meth:`Doubts.cut_off`): let go if the robot is seen again by the
        same process, taken at their deadline if it is still gone."""
        lost = getattr(self.deployer.transport, "router_link_lost", None)
        if self.doubts is None or lost is None:
            return
        if not lost():
            self._cut_off = False
            return
        self.doubts.cut_off(time.monotonic())
        self.coordinator.excuse(self.deployer.me, 2 * self.doubts.lease)
        if not self._cut_off:
            self._cut_off = True
            self.deployer.member.error(
                f"{self.deployer.me} lost its own link to the router; robots seen lost now "
                "are checked again before anything is withdrawn"
            )

    def _doubt(self, detection: Detection) -> bool:
        """Whether ``detection`` is held: a loss while losses are in doubt, or
        a robot seen again whose loss is held. Seen again by the same process,
        both are let go; seen before any process of it is (its two tokens come
        back one after the other), the loss stays held to its deadline
        (:meth:`_settle_doubts` decides). Seen again as another process (it
        was restarted meanwhile), its loss is taken first, then the sighting."""
        if self.doubts is None:
            return False
        if self.doubts.hold(detection, time.monotonic()):
            return True
        robot = detection.other
        if detection.kind == "seen" and robot in self.doubts.held:
            same = self._same_process(robot)
            if same is None:
                return True  # its process token is not back yet: decided at the deadline
            lost = self.doubts.seen(robot)
            if same:
                return True  # it never left: its loss was this robot's stall
            if lost is not None:
                self.take(lost)
        return False

    def _same_process(self, robot: str) -> bool | None:
        """Whether ``robot``'s accepted process still runs: its process token
        is seen (True), another one's is and not it (False), or its name is
        alive with no process token seen (None: not known yet). Without
        process tokens, whether the robot is alive."""
        current, live = self._instances.get(robot), self._processes.get(robot)
        alive = robot in self.deployer.transport.alive
        if current is None or live is None:
            return alive
        if current in live:
            return True
        return None if alive and not live else False

    def _settle_doubts(self) -> None:
        """At their deadline, take the held losses of robots not seen again
        by the same process; one that runs as another process is seen again
        too (its new process is greeted, as after :meth:`process`)."""
        if self.doubts is None:
            return
        for lost in self.doubts.due(time.monotonic()):
            robot = lost.other
            same = self._same_process(robot)
            if same:
                continue
            self.take(lost)
            if same is False and robot in self.deployer.transport.alive:
                me = self.deployer.me
                self.take(Detection("seen", me, time.time(), other=robot, how="process"))

    def take(self, detection: Detection) -> None:
        robot = detection.other
        if robot in self._hidden and detection.how != "process":
            self._hidden.discard(robot)
            if detection.kind == "lost":  # the name held after its process ended: taken already
                self._held.pop(robot, None)
                self.deployer.gone(robot)
                return
        if detection.kind == "seen" and robot not in self._present:
            if not self.deployer.seen(robot):
                self._held[robot] = detection  # taken once it says it is ready
                return
            self._present.add(robot)
            self.deployer.resync(robot)
        elif detection.kind == "lost":  # its token went (or it refused): ready no more
            self._told.discard(robot)
            self._present.discard(robot)
            self._held.pop(robot, None)
            self._instances.pop(robot, None)
            self.deployer.gone(robot)
        self.coordinator.handle(detection)

    def receiver(self, sender: str) -> Callable[[bytes], None]:
        """What reads the messages on ``sender``'s key to the coordinator."""
        return lambda payload: self.receive(payload, sender)

    def receive(self, payload: bytes, sender: str) -> None:
        """A report, an acknowledgement or a robot's word that it is ready, on
        ``sender``'s key: one that says it is from another robot is dropped."""
        if self.retired:
            return
        try:
            message = read_to_coordinator(payload)
        except ProtocolError as exc:
            said = f"a message to the coordinator that cannot be read: {exc}"
            self._say(f"{sender} unreadable {exc.kind}", said)
            return
        if message.robot != sender:
            said = f"a message on {sender}'s key that says it is from {message.robot!r}"
            self._once(f"{sender} names another", said)
        elif isinstance(message, Ack):
            if message.epoch == self.deployer.epoch:  # else: to the coordinator before this one
                self.deployer.acked(message.robot, message.id, message.phase, message.reason)
        elif isinstance(message, Ready):
            if not self._foreign(message.robot) and not self._duplicate(message):
                self._ready(message.robot)
        elif isinstance(message, Rival):
            self._rival(message)
        elif isinstance(message, CallError):
            said = f"{message.robot} {message.functionality}: {message.error}"
            self._say(f"{sender} call-error", said)
        else:
            self._report(message)

    def _report(self, report: Report) -> None:
        """A helper's detection. It speaks only for itself: a detection made
        on another robot is dropped (recorded), and so is one about what is not
        the helper's own (:func:`beyond_its_own`). Who is in the society is the
        coordinator's own liveliness view: a helper's ``lost`` or ``seen``
        says only how *it* sees the network (a helper frozen a while sees
        everyone lost once it runs again; a link between two helpers that
        dropped shows as stale inputs), so it is not acted on here."""
        detection = report.detection
        if detection.robot != report.robot:
            said = f"{report.robot} reported a detection made by {detection.robot!r}: dropped"
            self._say(f"{report.robot} another's detection", said)
            return
        beyond = beyond_its_own(detection)
        if beyond is not None:
            key = f"{report.robot} {detection.kind} beyond its own"  # a few kinds per robot
            self._once(key, f"{report.robot} reported {beyond}")
        elif detection.kind not in ("lost", "seen"):
            self.take(detection)

    def process(self, robot: str, instance: str, alive: bool) -> None:
        """A process of ``robot`` appeared or went (its process token, which
        :meth:`ZenohTransport.watch_processes` reports; its ``alive`` token
        shows two processes as one). A process that appears while the one
        the society runs with is alive is a second one — a robot frozen past
        the lease that comes back next to its replacement, or a second start
        — and is told ``duplicate`` (it stops). When the one the society runs
        with goes while another keeps the robot's name alive, the robot is
        lost (its part with it) and the other is asked whether it is ready,
        as a robot seen again is: otherwise the live name would hide that
        death until its inputs went stale."""
        if self.retired:
            return
        if robot == self.deployer.me:  # another process of this robot: a second coordinator
            (self._twins.add if alive else self._twins.discard)(instance)
            return
        if self.members and robot not in self.members:
            return  # a stranger's tokens are not kept
        live = self._processes.setdefault(robot, set())
        (live.add if alive else live.discard)(instance)
        current = self._instances.get(robot)
        if current is None or (instance == current and alive):
            return
        if alive and current in live:
            self.deployer.refuse(robot, instance)
            self._once(f"{robot} second process", f"a second process of robot {robot}")
        elif not alive and instance == current and live:
            me, now = self.deployer.me, time.time()
            gone = f"its process {instance} ended; another process of {robot} runs"
            self.take(Detection("lost", me, now, other=robot, how="process", detail=gone))
            self.take(Detection("seen", me, now, other=robot, how="process"))
        elif not alive and instance == current:  # its name should go with it: see _settle_ended
            self._ended[robot] = (instance, time.monotonic() + self.process_grace)

    def _settle_ended(self) -> None:
        """A robot whose process ended while its name stays alive for longer
        than :attr:`process_grace` — a session that declares no process of
        it holds its ``alive`` token (its key in other hands): the robot is
        lost, as if the token went, and greeted (a process of it started
        again answers and is taken back). The token's going later is not a
        second loss."""
        now = time.monotonic()
        for robot, (instance, deadline) in sorted(self._ended.items()):
            if now < deadline:
                continue
            del self._ended[robot]
            held = robot in self.deployer.transport.alive and not self._processes.get(robot)
            if not held or self._instances.get(robot) != instance:
                continue
            me, t = self.deployer.me, time.time()
            gone = (
                f"its process {instance} ended, but its name is still alive: a session that "
                f"declares no process of {robot} holds it"
            )
            self._once(f"{robot} name held", f"robot {robot}'s {gone}")
            self.take(Detection("lost", me, t, other=robot, how="process", detail=gone))
            self._hidden.add(robot)
            self.take(Detection("seen", me, t, other=robot, how="process"))

    def _say(self, key: str, said: str) -> None:
        """Say ``said`` (an ``error`` event), at most once a second for ``key``
        (a kind of message and its sender); the others of the second are
        counted and said as a count (:meth:`_say_counts`): a robot that sends
        a flood of them costs the loop and the trace one event a second."""
        if self._throttle.note(key, time.monotonic()):
            self.deployer.member.error(said)

    def _say_counts(self) -> None:
        """The messages :meth:`_say` counted, once their second is over."""
        for key, count in self._throttle.due(time.monotonic()):
            sender, _, kind = key.partition(" ")
            self.deployer.member.error(
                f"{count} more message(s) from {sender} ({kind}) in the last second or more: "
                "dropped"
            )

    def _once(self, key: str, said: str) -> None:
        """Say ``said`` (dropped), the first time for ``key``, for a few keys
        (each a robot of the state and a kind of message, so that no robot
        can use them up for the others)."""
        if key not in self._noted and len(self._noted) < 64:
            self._noted.add(key)
            self.deployer.member.error(f"{said}: dropped")

    def _foreign(self, robot: str) -> bool:
        """Whether ``robot`` runs another problem: a token of another problem is
        up under its name and none of this one's (a process started with an
        edited state; it stops by itself, :mod:`cfgplan.security.identity`).
        Its ``ready`` is not taken (said once): it is greeted on, and taken
        once a process of this problem runs it."""
        foreign = getattr(self.deployer.transport, "foreign", None)
        theirs = foreign(robot) if foreign is not None else None
        if theirs is None:
            return False
        self._once(
            f"{robot} another problem",
            f"robot {robot} runs another problem ({theirs}): not taken into the society "
            "until a process of its problem runs it",
        )
        return True

    def _duplicate(self, ready: Ready) -> bool:
        """Whether ``ready`` is from a second process of a robot whose first
        one is alive: it is told so (it stops) and nothing else is done."""
        robot, first = ready.robot, self._instances.get(ready.robot)
        if first is None or not ready.instance or robot not in self.deployer.transport.alive:
            if ready.instance:
                self._instances[robot] = ready.instance
                for other in sorted(self._processes.get(robot, set()) - {ready.instance}):
                    self.deployer.refuse(robot, other)  # its token came first: it is second
                    self._once(f"{robot} second process", f"a second process of robot {robot}")
            return False
        if ready.instance == first:
            return False
        self.deployer.refuse(robot, ready.instance)
        self._once(f"{robot} second process", f"a second process of robot {robot}")
        return True

    def _rival(self, rival: Rival) -> None:
        """A robot follows another coordinator: if it is this one that is the
        second, it stops — once what the robot says is borne out by this
        coordinator's own view (:meth:`_borne_out`), within a lease; else the
        console says a second one was refused. A robot that follows a run of
        a later generation than this one's fences this one off
        (:meth:`_later`); one that follows an older run is not believed (it
        still sees that run's coordinator, and follows this one once that
        one is gone)."""
        mine, over = generation(self.deployer.epoch), generation(rival.over)
        if rival.epoch == self.deployer.epoch and rival.over and over != mine:
            if over > mine:
                self._later(rival.robot, rival.leader, rival.over)
            else:
                self._once(
                    f"{rival.robot} older run",
                    f"{rival.robot} still follows an older run ({printable(rival.leader)}'s)",
                )
            return
        if rival.epoch == self.deployer.epoch:
            if self.refusal is None and rival.robot not in self._rivals:
                lease = getattr(self.deployer.transport, "lease", DEFAULT_LEASE)
                self._rivals[rival.robot] = (rival, time.monotonic() + lease)
                self._weigh_rivals()
            return
        self._once(
            f"{rival.robot} rival", f"a second coordinator of the society, refused by {rival.robot}"
        )

    def later(self, sender: str, epoch: str) -> None:
        """A message of ``sender``'s run ``epoch``, of a later generation than
        this coordinator's, reached its robot (:attr:`Member.on_later`)."""
        self._later(sender, sender, epoch)

    def _later(self, robot: str, leader: str, epoch: str) -> None:
        """``robot`` follows ``leader``'s run ``epoch``, of a later generation
        than this one's. If ``leader`` itself says so (its own key, or a
        message of its run to this robot), is alive and is the one next after
        this coordinator in the order of succession, it took over while this
        one stood still: this one steps down and follows it
        (:attr:`superseded`). Another robot's word is not enough — with its
        own valid key a helper could otherwise make the coordinator step down
        for a robot that coordinates nothing — and the successor's own
        greeting comes soon (it greets every robot it sees). If ``leader`` is
        gone, this coordinator counts a generation beyond it and sends
        ``robot`` its part again (a robot follows a later run once its
        coordinator is gone). Else it is not believed.

        Gone is not what this robot's session says at one moment: a process
        frozen past the lease lost every token, and its session takes them
        back only as it catches up, while the messages that waited meanwhile
        — the successor's greeting among them — are read. ``leader`` not
        alive here is weighed for a lease (:meth:`_weigh_claims`): seen alive
        meanwhile, it is decided as above; still gone at the end, this one
        counts beyond it."""
        if self.retired or self.superseded is not None:
            return  # decided already (a rival and the later run's own greeting, in one pass)
        gone = leader not in self.deployer.transport.alive
        if gone and leader != self.deployer.me and self._beyond(leader, epoch):
            if robot not in self._claims:
                lease = getattr(self.deployer.transport, "lease", DEFAULT_LEASE)
                self._claims[robot] = (leader, epoch, self.deployer.clock() + lease)
            return
        self._decide_later(robot, leader, epoch)

    def _beyond(self, leader: str, epoch: str) -> bool:
        """Whether this coordinator may count a generation beyond ``leader``'s
        run ``epoch`` once ``leader`` is gone."""
        return leader in self.coordinators and generation(epoch) < MAX_GENERATION

    def _weigh_claims(self) -> None:
        """The later runs held by :meth:`_later`: each decided once its leader
        is alive here, or once its lease is over."""
        now, alive = self.deployer.clock(), self.deployer.transport.alive
        for robot, (leader, epoch, deadline) in sorted(self._claims.items()):
            if leader in alive or now >= deadline:
                del self._claims[robot]
                self._decide_later(robot, leader, epoch)

    def _decide_later(self, robot: str, leader: str, epoch: str) -> None:
        """Step down for ``leader``, count beyond it, or go on (:meth:`_later`)."""
        if self.retired or self.superseded is not None:
            return
        me, over = self.deployer.me, generation(epoch)
        alive = self.deployer.transport.alive
        if robot == leader != me and leader in alive and leader in self.coordinators:
            nxt = (
                leader
                if self.succession is None
                else self.succession.successor(
                    self.deployer.step(), candidates(self.deployer.transport, me), me
                )
            )
            if nxt == leader:
                self.superseded = (leader, epoch)
                info = (("leader", leader), ("epoch", epoch), ("was", self.deployer.epoch))
                self.deployer.member.robot.record(
                    Adaptation(robot=me, t=time.time(), what="step-down", info=info)
                )
                return
        if leader not in alive and self._beyond(leader, epoch):
            raised = new_epoch(over + 1)
            self.deployer.epoch = self.deployer.member.epoch = raised
            if f"{robot} later run" not in self._noted:
                self._noted.add(f"{robot} later run")
                self.deployer.member.error(
                    f"{robot} followed a later run ({printable(leader)}'s, gone): this "
                    f"coordinator goes on as run {raised}"
                )
            self.deployer.resync(robot)
            return
        if robot != leader and leader in alive:
            return  # its leader's own word decides (:meth:`later`)
        self._once(
            f"{robot} later run not believed",
            f"{robot} follows a later run ({printable(leader)}'s), but that robot is not "
            "alive and next in the order of succession: not believed, this one goes on",
        )

    def retire(self) -> None:
        """This coordinator stepped down (:attr:`superseded`): it reads no more
        messages, its threads end, its losses are no longer watched."""
        self.retired = True
        listeners = getattr(self.deployer.transport, "presence_listeners", None)
        if listeners is not None and self._presence in listeners:
            listeners.remove(self._presence)
        self.close()

    def _borne_out(self, rival: Rival) -> bool:
        """Whether this coordinator's own view bears ``rival`` out. A robot that
        never said it is ready to this coordinator follows another one: its
        word is what the protocol goes by (a second coordinator that reaches
        only the helpers sees no more). One that did — it follows this one,
        its answers carry this one's epoch — contradicts itself, and is
        believed only if the leader it names is alive and may coordinate:
        another process of this very robot (its process token), or another
        robot that may (with keys, one ``society.json`` marks a coordinator;
        without, a robot of the state) and is not the robot that says it
        follows it. With its own valid key, a robot could otherwise stop the
        coordinator it follows by naming anyone."""
        if rival.robot not in self.deployer.ready:
            return True
        leader = rival.leader
        if leader == self.deployer.me:
            return bool(self._twins)
        if leader == rival.robot or leader not in self.coordinators:
            return False
        return leader in self.deployer.transport.alive

    def _weigh_rivals(self) -> None:
        """The rivals said: borne out, this coordinator stops; not borne out
        within a lease, it goes on, and says it did not believe them."""
        now = time.monotonic()
        for robot, (rival, deadline) in sorted(self._rivals.items()):
            if self._borne_out(rival):
                self.refusal = (
                    f"society {self.deployer.transport.society} has a coordinator already: "
                    f"{rival.robot} follows {rival.leader}; this one stops"
                )
                return
            if now >= deadline:
                del self._rivals[robot]
                self._once(
                    f"{robot} rival not believed",
                    f"{robot} says it follows another coordinator ({printable(rival.leader)}), "
                    "but no such coordinator runs: not believed, this one goes on",
                )

    def _ready(self, robot: str) -> None:
        """``robot`` can be sent its part: take it back if it was seen, else
        (said again, or before its token is seen) send it its part."""
        if robot == self.deployer.me:
            return
        self.deployer.said_ready(robot)
        self._told.discard(robot)  # a process that says so anew may know nothing yet
        self._hidden.discard(robot)  # a process of it answers: its losses are its own again
        held = self._held.pop(robot, None)
        if held is not None:
            self.take(held)
        else:
            self.deployer.resync(robot)

    @property
    def finished(self) -> str | None:
        """Why the run ends, once every robot was told and answered (or the wait is over)."""
        if self.refusal is not None:
            return REFUSED
        return self.coordinator.finished if self._silent is not None else None

    @property
    def stopped(self) -> bool:
        return self.coordinator.stopped

    def close(self) -> None:
        if self.heartbeat is not None:
            self.heartbeat.stop()
        self.coordinator.close()


def coordinate(
    society: Society,
    transport: ZenohTransport,
    task: Task,
    domain: Domain,
    goal: Ground,
    config: Configuration | None,
    parts: dict[str, Part],
    injections: Sequence[Injection] = (),
    *,
    hysteresis: Hysteresis | None = None,
    hold: float = HOLD,
    goals: tuple[Ground, ...] = (),
    timeout: float = SWITCH_TIMEOUT,
    kill: Callable[[str], None] | None = None,
    member: Member | None = None,
    generation: int = 1,
    step: int = 0,
    succession: Succession | None = None,
    situation: Situation | None = None,
) -> NetworkAdaptive:
    """Make the one robot of ``society`` the coordinator of its society, its
    run of ``generation`` (:func:`~cfgplan.runtime.protocol.new_epoch`);
    ``member``: the robot's member when it followed another coordinator
    until now (it takes over), ``step``: the step of the sequence ``goal``
    is (from 0), ``succession``: the order of succession, ``situation``: what
    the society committed on top of the state (:mod:`~cfgplan.reconfigure.committed`:
    a robot that takes over goes on from it)."""
    (robot,) = society.robots
    if member is None:
        member = Member(robot, transport, Monitor(hold=hold), forward=False, hold=hold)
        assert member.monitor is not None
        member.monitor.watch(robot)
    monitor = member.monitor
    assert monitor is not None
    presence = monitor.presence(robot.name)
    transport.presence_listeners.append(presence)
    member.succession = succession
    deployer = NetworkDeployer(transport, member, timeout, parts=dict(parts))
    deployer.epoch = new_epoch(generation)
    member.lead(deployer.epoch)
    reconfigurator = Reconfigurator(
        task,
        domain,
        goal,
        config,
        hysteresis or Hysteresis(),
        goals=goals,
        situation=situation or Situation(),
    )
    deployer.step_of = lambda: step + len(goals) - len(reconfigurator.goals)
    coordinator = Coordinator(
        reconfigurator,
        robot.record,
        robot.name,
        deployer,
        ahead=Ahead(reconfigurator),
        hold=hold,
        grace=2 * transport.lease,  # the lease runs out, and its loss is seen, first
        reported=transport.lease,
    )
    injector = Injector(injections, society, kill=kill)
    adaptive = NetworkAdaptive(coordinator, deployer, monitor, injector)
    adaptive.succession, adaptive._presence = succession, presence
    member.on_later = adaptive.later
    adaptive.members = frozenset(task.agents)
    adaptive.coordinators = coordinators_of(transport, adaptive.members)
    adaptive.heartbeat, adaptive.doubts = Heartbeat(), Doubts(transport.lease)
    adaptive.heartbeat.start()
    watch = getattr(transport, "watch_processes", None)
    if watch is not None:  # over Zenoh: each process of a robot has a token of its own
        watch(adaptive.process)
    for other in sorted(set(task.agents) - {robot.name}):  # each robot of the state, its own key
        transport.subscribe(coordinator_key(transport.society, other), adaptive.receiver(other))
        transport.declare(configure_key(transport.society, other))  # ready to talk to it
    return adaptive
