"""Global channels over Eclipse Zenoh: each robot its own process, on one host or many (5.2.2).

The thesis copies a global channel's data "through a socket connection"; here
each robot program opens one Zenoh session in *peer* mode (no router) and:

* declares itself with a liveliness token, ``cfgplan/<society>/<robot>/alive``,
  and its process with another, ``.../process/<instance>`` (so that the
  coordinator tells a second process of a robot from the first);
* subscribes to every global channel into it (one subscriber for the
  robot's ``ch/**``; a channel attached or detached is a dictionary entry, so
  a switch declares nothing), on the keys of :mod:`cfgplan.runtime.keys`,
  keeping only the newest message per channel (the channel of 5.2.2 holds
  one item) until the robot's loop polls;
* publishes each write on a global channel out of it to the key of the robot
  at the other end (``express``: sent at once, not batched);
* watches the liveliness tokens of the robots it exchanges data with, and
  reports each one that appears or is lost. A robot whose process dies is
  lost as soon as its connection closes; one that freezes (a stopped process,
  a hung machine, a cut cable) when the *lease* runs out without a word from
  it: :data:`~cfgplan.runtime.zenoh_config.DEFAULT_LEASE` seconds unless set.
  It watches every robot's token; a robot that follows and may never
  coordinate watches only those it needs (:meth:`ZenohTransport.narrow`), so
  that a robot lost among 50 is news to a few processes, not to all 50.

Addressing (:class:`~cfgplan.runtime.zenoh_config.ZenohOptions`): ``--listen``
and ``--connect`` endpoints (``tcp/192.168.1.7:7447``); without them, robots
find each other by multicast scouting on the local network, with them
multicast scouting is off. ``--society`` keeps societies on one network
apart. A robot given only ``--connect`` listens nowhere (Zenoh would listen
on every interface): it reaches out and cannot be reached — peers do not
route for one another, so in a society of three or more a robot that others
must reach is given ``--listen``. A Zenoh configuration file (JSON5, Zenoh's
own format) sets anything else: it goes on top of cfgplan's defaults
(:data:`~cfgplan.runtime.zenoh_config.DEFAULTS`: peer mode, the connection
retry, the lease, the time to open a link), which it keeps unless it sets
them, and the options given on the command line go on top of it
(:mod:`cfgplan.runtime.zenoh_config`). With ``--keys DIR`` (the society's
keys, made by ``cfgplan keys new``) every link is TLS with mutual
authentication and Zenoh's access control by certificate name
(:mod:`cfgplan.security.zenoh_tls`).

:mod:`zenoh` is imported only when a :class:`ZenohTransport` is made, so
``import cfgplan.runtime`` stays light.
"""

from __future__ import annotations

import json
import queue
import secrets
import threading
import time
from collections.abc import Callable, Collection
from typing import TYPE_CHECKING, Any

from cfgplan.runtime.errors import RunError, printable
from cfgplan.runtime.keys import (
    MAX_PROBLEM_KEY,
    alive_key,
    alive_pattern,
    channel_key,
    channels_pattern,
    planner_key,
    planner_of_token,
    planner_pattern,
    problem_key,
    problem_of_token,
    problem_pattern,
    process_key,
    process_of_token,
    process_pattern,
    robot_of_alive,
    unchunk,
)
from cfgplan.runtime.transport import ChannelKey, Presence, Receiver
from cfgplan.runtime.zenoh_config import (
    DEFAULT_LEASE,
    DEFAULT_SOCIETY,
    OPEN_TIMEOUT_MS,
    ZenohOptions,
    endpoint_problem,
    load_zenoh,
    reason,
    zenoh_config,
)
from cfgplan.security.identity import ProblemId, conflict_message, stranger_message
from cfgplan.security.rates import Buckets

if TYPE_CHECKING:
    pass

__all__ = [  # the configuration's names too, where the transport's users have found them
    "DEFAULT_LEASE",
    "DEFAULT_SOCIETY",
    "OPEN_TIMEOUT_MS",
    "ZenohOptions",
    "ZenohTransport",
    "endpoint_problem",
    "zenoh_config",
]


class ZenohTransport:
    """One robot program's connection to its society (a Zenoh peer session)."""

    def __init__(self, robot: str, options: ZenohOptions | None = None) -> None:
        self.robot = robot
        self.options = options or ZenohOptions()
        self.society = self.options.society
        z = self._z = load_zenoh()
        config = zenoh_config(self.options, robot)
        self.lease = float(json.loads(config.get_json("transport/link/tx/lease"))) / 1000
        """Seconds of silence after which a robot is lost (the session's lease)."""
        try:
            self._session = z.open(config)
        except z.ZError as exc:
            raise RunError(f"cannot open the Zenoh session: {reason(exc)}") from None
        self.instance = secrets.token_hex(8)
        """This process among the robot's (a frozen one may come back next to its
        replacement): its ``ready`` names it, and so does its process token."""
        try:
            live = self._session.liveliness()
            self._token = live.declare_token(alive_key(self.society, robot))
            self._process = live.declare_token(process_key(self.society, robot, self.instance))
        except z.ZError as exc:
            self._session.close()
            raise RunError(f"cannot declare {robot} alive: {reason(exc)}") from None
        self._lock = threading.Lock()
        self._router_drops = 0  # links to a router that closed, since the last ask
        self._router_events: Any = None
        if self.options.router:  # a client: its own link to the router may go
            self._router_events = self._session.info.declare_transport_events_listener(
                self._router_event
            )
        self._subscribers: list[Any] = []
        self._channels: Any = None  # the subscriber of cfgplan/<society>/<robot>/ch/**
        self._receivers: dict[str, Receiver] = {}  # by key expression (with the sender)
        self._attached: dict[ChannelKey, str] = {}  # each channel's key expression
        self._newest: dict[str, bytes] = {}  # per key, what arrived since the last poll
        self._arrived = threading.Event()
        self._publishers: dict[str, Any] = {}
        self._arrivals: queue.SimpleQueue[tuple[str, bool]] = queue.SimpleQueue()
        self._watch: tuple[frozenset[str], Presence] | None = None
        self._watcher: Any = None
        self._narrowed: set[str] | None = None  # the robots watched one by one (narrow())
        self.alive: set[str] = set()
        """Robots of the society whose liveliness token is seen (after
        :meth:`watch`): of every robot, or of those watched (:meth:`narrow`)."""
        self.presence_listeners: list[Presence] = []
        """Told of every robot of the society appearing or lost (the coordinator)."""
        self._processes: queue.SimpleQueue[tuple[str, str, bool]] = queue.SimpleQueue()
        self._process_watchers: list[Callable[[str, str, bool], None]] = []
        self._messages: queue.SimpleQueue[tuple[Callable[[bytes], None], bytes]] = (
            queue.SimpleQueue()
        )
        self.sent = 0
        self._buckets = Buckets(self.options.rates, lease=self.lease)
        self._control = Buckets(self.options.rates.for_control)  # the protocol's keys
        self.notices: list[Callable[[str, str | None], None]] = []
        """Told ``(message, channel)`` of the messages a flood cost, once per
        interval (:attr:`~cfgplan.security.rates.RateLimits.report_every`): the
        robot's :class:`~cfgplan.runtime.member.Member` records them."""
        self.conflict: str | None = None
        """Set when a robot of the society runs another problem: the run ends."""
        self.conflict_handled = False
        """True once the switch protocol's member ends the run itself on a
        :attr:`conflict` (exit status 1, :data:`~cfgplan.runtime.launch.REFUSED`);
        else :meth:`poll` raises it."""
        self._problem_token: Any = None
        self._problems: Any = None
        self._met = False  # a robot of this one's problem was seen: it is of their society
        self._aliens: dict[tuple[str, str], tuple[ProblemId, float]] = {}  # another problem's
        self._said_aliens: set[tuple[str, str]] = set()
        self._ours: set[str] = set()  # robots whose token of this one's problem is up
        self._planners: set[str] = set()  # those of them that plan it (their planner token)
        self._planner_token: Any = None
        self._planner_watch: Any = None
        self._up: set[tuple[str, str]] = set()  # the tokens of _aliens up now
        if self.options.problem is not None:
            self._announce(self.options.problem)
        self.dropped = 0
        """Messages dropped because :attr:`ZenohOptions.backlog` were waiting."""

    @property
    def session(self) -> Any:
        """The robot's Zenoh session, for what shares it (the ROS 2 bridge, :mod:`cfgplan.ros2`)."""
        return self._session

    def attach(self, robot: str, key: ChannelKey, receiver: Receiver, sender: str) -> None:
        """Messages on the key naming ``sender`` go to ``receiver``; one on the
        same channel's key naming another robot reaches nobody."""
        if robot != self.robot:
            raise RunError(f"this Zenoh session carries {self.robot}'s channels, not {robot}'s")
        if key in self._attached:
            raise RunError(f"channel {key} is created twice on {robot}")
        where = self._attached[key] = channel_key(self.society, robot, key, sender)
        with self._lock:
            self._receivers[where] = receiver
            self._buckets.open(where, time.monotonic())
        if self._channels is None:  # one subscriber for every channel into this robot
            every = channels_pattern(self.society, robot)
            self._channels = self._session.declare_subscriber(every, self._on_sample)
            self._subscribers.append(self._channels)

    def detach(self, robot: str, key: ChannelKey) -> None:
        """Nothing more is handed to channel ``key`` (what still arrives is dropped)."""
        where = self._attached.pop(key, None)
        if where is None:
            return
        with self._lock:
            self._receivers.pop(where, None)
            self._newest.pop(where, None)
            self._buckets.close(where)

    def pace(self, key: ChannelKey, period: float | None) -> None:
        """The sender of channel ``key`` states ``period``: what the channel takes
        follows it (:meth:`~cfgplan.security.rates.Buckets.pace`)."""
        where = self._attached.get(key)
        if where is not None:
            with self._lock:
                self._buckets.pace(where, period)

    def subscribe(self, key: str, handler: Callable[[bytes], None]) -> None:
        """Every message on ``key`` (in order) to ``handler``, at :meth:`poll`:
        the reconfiguration protocol's messages. ``key`` is one sender's (a
        robot's key to the coordinator, a robot's ``configure``): at most
        :attr:`~cfgplan.security.rates.RateLimits.control` of them a second
        are taken, after a burst (:mod:`cfgplan.security.rates`), the rest
        dropped unread and said once per interval (:attr:`notices`)."""

        with self._lock:
            self._control.open(key, time.monotonic())

        def queue_it(sample: Any) -> None:
            with self._lock:  # each such key is one sender's: bounded like a channel
                if not self._control.admit(key, time.monotonic()):
                    return
            if self._messages.qsize() >= self.options.backlog:
                self.dropped += 1
                return
            self._messages.put((handler, sample.payload.to_bytes()))
            self._arrived.set()

        self._subscribers.append(self._session.declare_subscriber(key, queue_it))

    def publish(self, key: str, payload: bytes) -> None:
        """Send ``payload`` on ``key`` now (reliable, not batched)."""
        self.declare(key).put(payload)

    def declare(self, key: str) -> Any:
        """The publisher of ``key``, declared now if it is not yet (declaring
        ahead saves the first message the declaration's time)."""
        publisher = self._publishers.get(key)
        if publisher is None:
            publisher = self._session.declare_publisher(key, express=True)
            self._publishers[key] = publisher
        return publisher

    def _on_sample(self, sample: Any) -> None:
        """On a Zenoh thread: keep the newest message of its channel for
        :meth:`poll`, if its bucket takes it (:mod:`cfgplan.security.rates`):
        a message dropped is not read, kept nor woken for."""
        where = str(sample.key_expr)
        with self._lock:
            if not self._buckets.admit(where, time.monotonic()):
                return
            self._newest[where] = sample.payload.to_bytes()
        self._arrived.set()

    def _announce(self, problem: ProblemId) -> None:
        """Declare the problem token and watch the society's (module
        :mod:`cfgplan.security.identity`)."""
        about = problem.about
        key = problem_key(self.society, self.robot, problem.fingerprint, about)
        while len(key) > MAX_PROBLEM_KEY and about:  # what the others read (escapes are long)
            about = about[: len(about) // 2]
            key = problem_key(self.society, self.robot, problem.fingerprint, about)
        liveliness = self._session.liveliness()
        try:  # watching first: a robot that refuses at the sight of this token
            # has answered the watch (with its own token) before it leaves
            self._problems = liveliness.declare_subscriber(
                problem_pattern(self.society), self._on_problem, history=True
            )
            self._problem_token = liveliness.declare_token(key)
            if self.options.plans:  # it may take over coordination: the others know, it knows
                self._planner_watch = liveliness.declare_subscriber(
                    planner_pattern(self.society), self._on_planner, history=True
                )
                planner = planner_key(self.society, self.robot, problem.fingerprint)
                self._planner_token = liveliness.declare_token(planner)
        except self._z.ZError as exc:
            self.close()
            raise RunError(f"cannot announce {self.robot}'s problem: {reason(exc)}") from None

    def _on_planner(self, sample: Any) -> None:
        """On a Zenoh thread: a robot says it runs this robot's problem with the
        planner (:attr:`ZenohOptions.plans`), or no longer does."""
        mine = self.options.problem
        named = planner_of_token(str(sample.key_expr), self.society)
        if mine is None or named is None or named[1] != mine.fingerprint:
            return
        robot = named[0]
        with self._lock:
            if sample.kind != self._z.SampleKind.PUT:
                self._planners.discard(robot)
            elif robot != self.robot and len(self._planners) < 4096:
                self._planners.add(robot)

    def _on_problem(self, sample: Any) -> None:
        """On a Zenoh thread: a robot of the society says which problem it runs
        (:mod:`cfgplan.security.identity`). A robot of this one's problem,
        another than this one, makes it a member of its society for good; one
        of another problem is kept for :meth:`_weigh` (which goes by what was
        seen: a robot out of place that met the other stops, even if the
        other left first) and, while its token is up, for :meth:`foreign`."""
        mine = self.options.problem
        named = problem_of_token(str(sample.key_expr), self.society)
        if mine is None or named is None:
            return
        robot, fingerprint, about = named
        if sample.kind != self._z.SampleKind.PUT:
            with self._lock:  # (a robot out of place decides by what it saw: _aliens stay)
                self._up.discard((robot, fingerprint))
                if fingerprint == mine.fingerprint:
                    self._ours.discard(robot)
            return
        if fingerprint == mine.fingerprint:
            if robot != self.robot:
                self._met = True
                with self._lock:
                    if len(self._ours) < 4096:
                        self._ours.add(robot)
            return
        try:
            theirs = ProblemId(fingerprint, about)
        except ValueError:  # not a fingerprint: not written by cfgplan
            return
        with self._lock:
            if len(self._aliens) < 64:
                self._aliens.setdefault((robot, fingerprint), (theirs, time.monotonic()))
                self._up.add((robot, fingerprint))
        self._arrived.set()

    def planners(self) -> set[str]:
        """The other robots that say they run this robot's problem with the
        planner (their planner token is up; a robot run from emitted code
        announces its problem, not this): they may take over coordination
        (:func:`cfgplan.runtime.succession.candidates`)."""
        with self._lock:
            return set(self._planners)

    def foreign(self, robot: str) -> ProblemId | None:
        """The other problem ``robot`` runs, if a token of another problem is up
        under its name and none of this one's: a process started with another
        state, which the coordinator does not take into its society."""
        with self._lock:
            if robot in self._ours:
                return None
            up = sorted((k, v) for k, v in self._aliens.items() if k in self._up)
            return next((p for (r, _), (p, _) in up if r == robot), None)

    def _weigh(self, now: float) -> None:
        """A robot of another problem is in the society: if this robot met one
        of its own problem (it is a member of a society running it), that
        one is not of its society and is said once (:attr:`notices`), never
        acted on — else any token under any name would stop the society.
        Otherwise this robot is the one out of place (it was started with an
        edited state, or in another team's society): a lease after it saw
        the other's token (gone since or not), with no robot of its own
        problem seen, it stops (:attr:`conflict`)."""
        mine = self.options.problem
        if mine is None or self.conflict is not None:
            return
        with self._lock:
            aliens = sorted(self._aliens.items())
        for (robot, fingerprint), (theirs, since) in aliens:
            name = printable(robot[:64])
            if self._met:
                if (robot, fingerprint) not in self._said_aliens and len(self._said_aliens) < 64:
                    self._said_aliens.add((robot, fingerprint))
                    said = stranger_message(self.society, mine, name, theirs)
                    for notice in self.notices:
                        notice(said, None)
            elif now - since >= self.lease:
                self.conflict = conflict_message(self.society, mine, name, theirs)
                return

    def send(self, key: ChannelKey, robot: str, payload: bytes) -> None:
        where = channel_key(self.society, robot, key, self.robot)
        publisher = self._publishers.get(where)
        if publisher is None:
            publisher = self._session.declare_publisher(where, express=True)
            self._publishers[where] = publisher
        publisher.put(payload)
        self.sent += 1

    def _router_event(self, event: Any) -> None:
        if event.kind == self._z.SampleKind.DELETE and event.transport.whatami == (
            self._z.WhatAmI.ROUTER
        ):
            with self._lock:
                self._router_drops += 1

    def router_link_lost(self) -> bool:
        """Whether this robot, a client of a router (``--router``), lost its
        own link to it since the last ask, or has none now. Every robot it
        watched then goes at once in its session, lost or not: a router that
        stopped reading this robot's link past the lease (another client's
        lossy link held it up) drops it, and it connects again a moment
        later. Always false for a peer.

        Zenoh closes the link first, then tells the liveliness subscribers
        (the losses), then the transport's listeners: a loss already drained
        may come before the event, but never while the link is still listed."""
        if self._router_events is None:
            return False
        with self._lock:
            drops, self._router_drops = self._router_drops, 0
        return drops > 0 or not list(self._session.info.links())

    def narrow(self, robots: Collection[str]) -> None:
        """Watch the liveliness of ``robots`` only (and whether they plan, their
        planner tokens), and, as they come, of the partners (:meth:`watch`)
        and of the coordinator followed (:meth:`watch_robot`), not every
        robot's; and stop watching the problem tokens once a robot of this
        one's problem is met (it is then a member, which no other problem's
        token stops, :mod:`cfgplan.security.identity`; the coordinator says
        who is not of the society). For a robot that follows and never
        coordinates (``robots``: the coordinator and those that may take over,
        :mod:`cfgplan.reconfigure.owner`): every robot lost or back otherwise
        reaches every process of the society and wakes it, 49 of them at once
        among 50 robots, while the coordinator switches. Before :meth:`watch`."""
        self._narrowed = set()
        if self._planner_watch is not None:  # every robot's: those of ``robots`` instead
            self._planner_watch.undeclare()
            self._planner_watch = None
            with self._lock:
                self._planners.clear()
        for name in sorted(robots):
            self.watch_robot(name)

    def watch_robot(self, name: str) -> None:
        """Watch ``name``'s liveliness (and its planner token) too, if only
        some robots' is watched (:meth:`narrow`): its token, up now, is
        reported as its subscriber's history arrives (milliseconds)."""
        if self._narrowed is None or name in self._narrowed or name == self.robot:
            return
        self._narrowed.add(name)
        liveliness = self._session.liveliness()
        watched = liveliness.declare_subscriber(
            alive_key(self.society, name), self._on_token, history=True
        )
        self._subscribers.append(watched)
        problem = self.options.problem
        if self.options.plans and problem is not None:
            planner = planner_key(self.society, name, problem.fingerprint)
            self._subscribers.append(
                liveliness.declare_subscriber(planner, self._on_planner, history=True)
            )

    def watch(self, robot: str, partners: Collection[str], report: Presence) -> None:
        """Report ``partners`` appearing and lost; called again (after a
        switch) it changes the partners, and a new partner already seen is
        reported seen at once."""
        first = self._watch is None  # what is seen until now is queued, reported at poll
        before = self._watch[0] if self._watch is not None else frozenset()
        self._watch = (frozenset(partners), report)
        if self._narrowed is not None:
            for name in sorted(partners):
                self.watch_robot(name)
            if first:
                return
        elif self._watcher is None:
            self._watcher = self._session.liveliness().declare_subscriber(
                alive_pattern(self.society), self._on_token, history=True
            )
            return
        with self._lock:
            alive = set(self.alive)
        for name in sorted((set(partners) - before) & alive):
            self._arrivals.put((name, True))

    def watch_processes(self, report: Callable[[str, str, bool], None]) -> None:
        """Report ``(robot, instance, alive)`` for every process of the
        society's robots but this one appearing or going (:func:`process_key`), on
        the loop's thread, as :meth:`poll` hands over (the coordinator: a
        robot's ``alive`` token shows two processes as one)."""
        if not self._process_watchers:
            self._subscribers.append(
                self._session.liveliness().declare_subscriber(
                    process_pattern(self.society), self._on_process, history=True
                )
            )
        self._process_watchers.append(report)

    def _on_process(self, sample: Any) -> None:
        """On a Zenoh thread: queue a process token's change for :meth:`poll`."""
        named = process_of_token(str(sample.key_expr), self.society)
        if named is None or named == (self.robot, self.instance):
            return  # (another process of this robot is reported: a second coordinator)
        self._processes.put((*named, sample.kind == self._z.SampleKind.PUT))
        self._arrived.set()

    def _on_token(self, sample: Any) -> None:
        """On a Zenoh thread: note who is alive, queue the change for :meth:`poll`."""
        name = robot_of_alive(str(sample.key_expr), self.society)
        if name is None or name == self.robot:
            return
        alive = sample.kind == self._z.SampleKind.PUT
        with self._lock:
            (self.alive.add if alive else self.alive.discard)(name)
        self._arrivals.put((name, alive))
        self._arrived.set()

    def wait(self, timeout: float) -> bool:
        """Block until a message has arrived (then :meth:`poll` hands it over),
        at most ``timeout`` seconds; whether one did."""
        return self._arrived.wait(timeout)

    def poll(self) -> None:
        """Hand over what arrived; :class:`RunError` when a robot of the
        society runs another problem (:attr:`conflict`) and nothing else ends the run."""
        if self._aliens:
            self._weigh(time.monotonic())
        if self._narrowed is not None and self._met and self._problems is not None:
            self._problems.undeclare()  # a member: no other problem's token concerns it
            self._problems = None
        if self.conflict is not None and not self.conflict_handled:
            raise RunError(self.conflict, hint="robots of one problem share a society name")
        with self._lock:
            newest, self._newest = self._newest, {}
            self._arrived.clear()
            now = time.monotonic()
            drops, control = self._buckets.due(now), self._control.due(now)
        self._say_drops(drops)
        self._say_control_drops(control)
        for where, payload in newest.items():
            receiver = self._receivers.get(where)
            if receiver is not None:
                receiver(payload)
        while True:
            try:
                handler, message = self._messages.get_nowait()
            except queue.Empty:
                break
            handler(message)
        while True:
            try:
                name, alive = self._arrivals.get_nowait()
            except queue.Empty:
                break
            if self._watch is not None and name in self._watch[0]:
                self._watch[1](name, alive)
            for listener in self.presence_listeners:
                listener(name, alive)
        while True:
            try:
                robot, instance, present = self._processes.get_nowait()
            except queue.Empty:
                break
            for watcher in self._process_watchers:
                watcher(robot, instance, present)

    def _say_drops(self, drops: list[tuple[str, int, float]]) -> None:
        """Tell :attr:`notices` of the messages a flood cost (once per interval)."""
        if not drops:
            return
        names = {where: key for key, where in self._attached.items()}
        every = self.options.rates.report_every
        for where, count, rate in drops:
            key = names.get(where)
            channel = str(key) if key is not None else where
            sender = unchunk(where.split("/")[4]) if key is not None else "?"
            said = (
                f"channel {channel} from {sender}: {count} message(s) over the rate limit "
                f"({rate:g} per second) dropped in the last {every:g} s or more (a robot floods "
                "it, or a stall longer than the lease held more back)"
            )
            for notice in self.notices:
                notice(said, channel)

    def _say_control_drops(self, drops: list[tuple[str, int, float]]) -> None:
        """Tell :attr:`notices` of the protocol's messages a flood cost, per key."""
        every = self.options.rates.report_every
        for where, count, rate in drops:
            said = (
                f"{count} message(s) of the switch protocol on {where} over the rate limit "
                f"({rate:g} per second) dropped in the last {every:g} s or more (its sender "
                "floods it)"
            )
            for notice in self.notices:
                notice(said, None)

    @property
    def control_dropped(self) -> int:
        """Messages of the switch protocol the rate limits dropped."""
        with self._lock:
            return self._control.dropped

    @property
    def rate_dropped(self) -> int:
        """Messages the rate limits dropped, on the channels attached now."""
        with self._lock:
            return self._buckets.dropped

    def close(self) -> None:
        """Leave: the token goes, so the others see this robot lost at once."""
        if self._session.is_closed():
            return
        for token in (self._planner_token, self._problem_token):
            if token is not None:
                token.undeclare()
        self._process.undeclare()
        self._token.undeclare()
        self._session.close()
