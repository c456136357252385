"""Global channels over Eclipse Zenoh: each robot its own process, on one host or many (5.2.2).

The thesis copies a global channel's data "through a socket connection"; here
each robot program opens one Zenoh session in *peer* mode (no router) and:

* declares itself with a liveliness token, ``cfgplan/<society>/<robot>/alive``;
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
  it: :data:`DEFAULT_LEASE` seconds unless set.

Addressing (:class:`ZenohOptions`): ``--listen`` and ``--connect`` endpoints
(``tcp/192.168.1.7:7447``); without them, robots find each other by
multicast scouting on the local network, with them multicast scouting is off.
``--society`` keeps societies on one network apart. A robot given only
``--connect`` listens nowhere (Zenoh would listen on every interface): it
reaches out and cannot be reached — peers do not route for one another, so
in a society of three or more a robot that others must reach is given
``--listen``. A Zenoh configuration file (JSON5, Zenoh's own format) sets
anything else: it goes on top of cfgplan's defaults (:data:`DEFAULTS`: peer
mode, the connection retry, the lease, the time to open a link), which it
keeps unless it sets them, and the options given on the command line go on
top of it. With ``--keys
DIR`` (the society's keys, made by ``cfgplan keys new``) every link is TLS
with mutual authentication and Zenoh's access control by certificate name
(:mod:`cfgplan.security.zenoh_tls`).

:mod:`zenoh` is imported only when a :class:`ZenohTransport` is made, so
``import cfgplan.runtime`` stays light.
"""

from __future__ import annotations

import json
import queue
import re
import threading
import time
from collections.abc import Callable, Collection
from dataclasses import dataclass, field
from types import ModuleType
from typing import TYPE_CHECKING, Any

from cfgplan.runtime.errors import RunError, printable
from cfgplan.runtime.keys import (
    MAX_PROBLEM_KEY,
    alive_key,
    alive_pattern,
    channel_key,
    channels_pattern,
    problem_key,
    problem_of_token,
    problem_pattern,
    robot_of_alive,
    unchunk,
)
from cfgplan.runtime.transport import ChannelKey, Presence, Receiver
from cfgplan.security.identity import ProblemId, conflict_message
from cfgplan.security.rates import Buckets, RateLimits

if TYPE_CHECKING:
    import zenoh

__all__ = [
    "DEFAULT_LEASE",
    "DEFAULT_SOCIETY",
    "ZenohOptions",
    "ZenohTransport",
    "endpoint_problem",
    "zenoh_config",
]

DEFAULT_LEASE = 2.0
"""Seconds without a word after which a frozen robot is reported lost (Zenoh's lease).

Long enough to ride out a TCP stall on a lossy link: the kernel resends a lost
segment after 200 ms, 400 ms, 800 ms, ..., so three losses of one segment
stall a link 1.4 s. With a 1 s lease that happened in one of three 30 s runs at
10 % loss (the robot reported lost, the society stopped 0.4 s); with 2 s, four
losses in a row are needed. A robot that dies is seen at once all the same
(its connection closes); only a frozen robot or a cut link waits for the lease
(issue 33; ``python -m benchmarks.faults``)."""

DEFAULT_SOCIETY = "default"
RETRY = '{"period_init_ms": 250, "period_max_ms": 500, "period_increase_factor": 2}'
"""Connecting to a robot that is not up yet (or not reachable) is retried every
half second at most."""

OPEN_TIMEOUT_MS = 1500
"""Milliseconds one attempt to open a link may take before it is given up and
retried. Zenoh's default, 10 s, bounds the TCP connect as well, and a connect
whose SYN was lost to a bad link waits for the kernel's resends (after 1 s, then
2 s, 4 s, ...) however long ago the link came back (issue 33: 2.8 s to reconnect
after 50 % loss cleared). Given up after 1.5 s (past the first resend), and
retried :data:`RETRY` 0.5 s later, an attempt goes out on the link at least
every second. A link that needs longer to open (a TLS handshake over a link of
300 ms round trips) needs a longer one: a ``--zenoh-config`` file's
``transport/unicast/open_timeout``."""

ENDPOINT = re.compile(r"^[A-Za-z0-9+.-]+/\S+$")
ENDPOINT_HINT = "e.g. tcp/127.0.0.1:7447, tcp/[::1]:7447 or tcp/robot-1.local:7447"


def endpoint_problem(text: str) -> str | None:
    """What is wrong with an endpoint's form (``None``: nothing Zenoh would not check)."""
    if ENDPOINT.match(text):
        return None
    return f"{text!r}: an endpoint is PROTOCOL/ADDRESS ({ENDPOINT_HINT})"


@dataclass(frozen=True)
class ZenohOptions:
    """How a robot program reaches the others."""

    society: str = DEFAULT_SOCIETY
    listen: tuple[str, ...] = ()
    connect: tuple[str, ...] = ()
    config_file: str | None = None
    lease: float | None = None  # seconds; None: the file's, else DEFAULT_LEASE
    keys: str | None = None  # a folder of society keys: TLS, mTLS, access control
    backlog: int = 10_000
    """Switch-protocol messages that may wait for the robot's loop; past it,
    more are dropped and counted (:attr:`ZenohTransport.dropped`): a robot
    that floods the coordinator cannot grow its memory without bound."""
    rates: RateLimits = field(default_factory=RateLimits)
    """How many messages per channel and sender are taken (:mod:`cfgplan.security.rates`)."""
    problem: ProblemId | None = None
    """The problem the robot runs, announced and checked against the society's
    (:mod:`cfgplan.security.identity`); ``None``: not known, not checked."""

    def __post_init__(self) -> None:
        if not self.society:
            raise RunError("the society name is empty")
        for option, endpoints in (("--listen", self.listen), ("--connect", self.connect)):
            for endpoint in endpoints:
                problem = endpoint_problem(endpoint)
                if problem:
                    raise RunError(f"{option} {problem}", hint=ENDPOINT_HINT)
        if self.lease is not None and not self.lease > 0:
            raise RunError(f"--lease {self.lease}: the lease must be a positive number of seconds")


def _zenoh() -> ModuleType:
    try:
        import zenoh
    except ImportError:
        raise RunError(
            "the Zenoh transport needs the eclipse-zenoh package, which is not installed",
            hint="pip install eclipse-zenoh",
        ) from None
    return zenoh


def _reason(exc: BaseException) -> str:
    """Zenoh's message without the Rust source location it appends."""
    text = str(exc)
    inner = re.search(r'msg: "(.*?)"', text)
    if inner:
        text = inner.group(1)
    return re.sub(r" at \S+\.rs:\d+\.?", "", text).strip()


DEFAULTS: tuple[tuple[str, str, str], ...] = (
    ("mode", '"peer"', "peer mode"),
    ("connect/retry", RETRY, "the connection retry"),
    ("transport/link/tx/lease", str(round(DEFAULT_LEASE * 1000)), "the lease"),
    ("transport/unicast/open_timeout", str(OPEN_TIMEOUT_MS), "the time to open a link"),
)
"""cfgplan's settings under anything a ``--zenoh-config`` file sets: (key, JSON5, what)."""


def zenoh_config(options: ZenohOptions, robot: str | None = None) -> zenoh.Config:
    """The session configuration of a robot program: cfgplan's :data:`DEFAULTS`
    (peer mode, the connection retry, a lease of :data:`DEFAULT_LEASE` s, an
    :data:`OPEN_TIMEOUT_MS` to open a link), then a configuration file's
    settings, then the options.

    A file is read whole by Zenoh, which fills in its own default for every
    key the file leaves out; so a key whose value in the file is Zenoh's own
    default counts as not set, and gets cfgplan's (``--lease 10`` asks for
    Zenoh's 10 s lease)."""
    z = _zenoh()
    config: zenoh.Config
    if options.config_file is not None:
        try:
            config = z.Config.from_file(options.config_file)
        except z.ZError as exc:
            raise RunError(
                f"cannot read the Zenoh configuration {options.config_file}: {_reason(exc)}"
            ) from None
        zenohs = z.Config()
        for key, value, what in DEFAULTS:
            if config.get_json(key) == zenohs.get_json(key):  # the file leaves it
                _set(config, key, value, what)
    else:
        config = z.Config()
        for key, value, what in DEFAULTS:
            _set(config, key, value, what)
    if options.listen:
        _set(config, "listen/endpoints", json.dumps(list(options.listen)), "--listen")
    elif options.connect and config.get_json("listen/endpoints") == z.Config().get_json(
        "listen/endpoints"
    ):  # it reaches out; Zenoh's default would listen on every interface
        _set(config, "listen/endpoints", "[]", "--connect (listens nowhere)")
    if options.connect:
        _set(config, "connect/endpoints", json.dumps(list(options.connect)), "--connect")
    if options.listen or options.connect:
        _set(config, "scouting/multicast/enabled", "false", "scouting")
    if options.lease is not None:
        _set(config, "transport/link/tx/lease", str(max(1, round(options.lease * 1000))), "--lease")
    if options.keys is not None:  # last: every endpoint, the file's too, becomes TLS
        from cfgplan.security.zenoh_tls import secure

        if robot is None:
            raise RunError("--keys: whose keys? (no robot named)")
        secure(config, options.keys, robot, options.society, _set)
    return config


def _set(config: Any, key: str, value: str, option: str) -> None:
    try:
        config.insert_json5(key, value)
    except Exception as exc:  # zenoh.ZError; zenoh is imported lazily
        raise RunError(f"{option}: Zenoh refuses {value}: {_reason(exc)}") from None


class ZenohTransport:
    """One robot program's connection to its society (a Zenoh peer session)."""

    def __init__(self, robot: str, options: ZenohOptions | None = None) -> None:
        self.robot = robot
        self.options = options or ZenohOptions()
        self.society = self.options.society
        z = self._z = _zenoh()
        config = zenoh_config(self.options, robot)
        self.lease = float(json.loads(config.get_json("transport/link/tx/lease"))) / 1000
        """Seconds of silence after which a robot is lost (the session's lease)."""
        try:
            self._session = z.open(config)
        except z.ZError as exc:
            raise RunError(f"cannot open the Zenoh session: {_reason(exc)}") from None
        try:
            self._token = self._session.liveliness().declare_token(alive_key(self.society, robot))
        except z.ZError as exc:
            self._session.close()
            raise RunError(f"cannot declare {robot} alive: {_reason(exc)}") from None
        self._subscribers: list[Any] = []
        self._channels: Any = None  # the subscriber of cfgplan/<society>/<robot>/ch/**
        self._receivers: dict[str, Receiver] = {}  # by key expression (with the sender)
        self._attached: dict[ChannelKey, str] = {}  # each channel's key expression
        self._newest: dict[str, bytes] = {}  # per key, what arrived since the last poll
        self._lock = threading.Lock()
        self._arrived = threading.Event()
        self._publishers: dict[str, Any] = {}
        self._arrivals: queue.SimpleQueue[tuple[str, bool]] = queue.SimpleQueue()
        self._watch: tuple[frozenset[str], Presence] | None = None
        self._watcher: Any = None
        self.alive: set[str] = set()
        """Robots of the society whose liveliness token is seen (after :meth:`watch`)."""
        self.presence_listeners: list[Presence] = []
        """Told of every robot of the society appearing or lost (the coordinator)."""
        self._messages: queue.SimpleQueue[tuple[Callable[[bytes], None], bytes]] = (
            queue.SimpleQueue()
        )
        self.sent = 0
        self._buckets = Buckets(self.options.rates)
        self.notices: list[Callable[[str, str], None]] = []
        """Told ``(message, channel)`` of the messages a flood cost, once per interval
        (:attr:`RateLimits.report_every`): the robot's :class:`~cfgplan.runtime.member.Member`
        records them."""
        self.conflict: str | None = None
        """Set when a robot of the society runs another problem: the run ends."""
        self.conflict_handled = False
        """True once the switch protocol's member ends the run itself on a
        :attr:`conflict` (exit status 1, :data:`~cfgplan.runtime.launch.REFUSED`);
        else :meth:`poll` raises it."""
        self._problem_token: Any = None
        self._problems: Any = None
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
        """Every message on ``key`` (in order, none dropped) to ``handler``, at
        :meth:`poll`: the reconfiguration protocol's messages."""

        def queue_it(sample: Any) -> None:
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
        except self._z.ZError as exc:
            self.close()
            raise RunError(f"cannot announce {self.robot}'s problem: {_reason(exc)}") from None

    def _on_problem(self, sample: Any) -> None:
        """On a Zenoh thread: a robot of the society says which problem it runs."""
        mine = self.options.problem
        named = problem_of_token(str(sample.key_expr), self.society)
        if mine is None or named is None or sample.kind != self._z.SampleKind.PUT:
            return
        robot, fingerprint, about = named
        if fingerprint == mine.fingerprint or self.conflict is not None:
            return
        try:
            theirs = ProblemId(fingerprint, about)
        except ValueError:  # not a fingerprint: not written by cfgplan
            return
        self.conflict = conflict_message(self.society, mine, printable(robot[:64]), theirs)
        self._arrived.set()

    def send(self, key: ChannelKey, robot: str, payload: bytes) -> None:
        where = channel_key(self.society, robot, key, self.robot)
        publisher = self._publishers.get(where)
        if publisher is None:
            publisher = self._session.declare_publisher(where, express=True)
            self._publishers[where] = publisher
        publisher.put(payload)
        self.sent += 1

    def watch(self, robot: str, partners: Collection[str], report: Presence) -> None:
        """Report ``partners`` appearing and lost; called again (after a
        switch) it changes the partners, and a new partner already seen is
        reported seen at once."""
        before = self._watch[0] if self._watch is not None else frozenset()
        self._watch = (frozenset(partners), report)
        if self._watcher is None:
            self._watcher = self._session.liveliness().declare_subscriber(
                alive_pattern(self.society), self._on_token, history=True
            )
            return
        with self._lock:
            alive = set(self.alive)
        for name in sorted((set(partners) - before) & alive):
            self._arrivals.put((name, True))

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
        if self.conflict is not None and not self.conflict_handled:
            raise RunError(self.conflict, hint="robots of one problem share a society name")
        with self._lock:
            newest, self._newest = self._newest, {}
            self._arrived.clear()
            drops = self._buckets.due(time.monotonic())
        self._say_drops(drops)
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
                f"({rate:g} per second) dropped in the last {every:g} s or more (a robot floods it)"
            )
            for notice in self.notices:
                notice(said, channel)

    @property
    def rate_dropped(self) -> int:
        """Messages the rate limits dropped, on the channels attached now."""
        with self._lock:
            return self._buckets.dropped

    def close(self) -> None:
        """Leave: the token goes, so the others see this robot lost at once."""
        if self._session.is_closed():
            return
        if self._problem_token is not None:
            self._problem_token.undeclare()
        self._token.undeclare()
        self._session.close()
