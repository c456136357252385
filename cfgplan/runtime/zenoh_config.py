"""A robot's Zenoh session configuration: cfgplan's defaults, a file's, the
command line's options (5.2.2; the timing a bad network needs, the keys of a secured society).

:func:`zenoh_config` builds it in layers: cfgplan's :data:`DEFAULTS` (peer
mode, the connection retry, the lease, the time to open a link), then a
``--zenoh-config`` file's settings (it keeps cfgplan's unless it sets them),
then the options of :class:`ZenohOptions` (endpoints, scouting, lease, keys).
:mod:`zenoh` is imported only when a configuration is made.
"""

from __future__ import annotations

import json
import os
import re
from dataclasses import dataclass, field
from types import ModuleType
from typing import TYPE_CHECKING, Any

from cfgplan.runtime.errors import RunError
from cfgplan.security.identity import ProblemId
from cfgplan.security.rates import RateLimits

if TYPE_CHECKING:
    import zenoh

__all__ = [
    "DEFAULTS",
    "DEFAULT_LEASE",
    "DEFAULT_SOCIETY",
    "OPEN_TIMEOUT_MS",
    "RETRY",
    "RUNTIME_THREADS",
    "STUCK_LINK",
    "WAIT_BEFORE_CLOSE",
    "ZenohOptions",
    "endpoint_problem",
    "follow_lease",
    "load_zenoh",
    "put_setting",
    "read_config",
    "reason",
    "spare_threads",
    "stuck_link_wait",
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
(``python -m benchmarks.faults``)."""

DEFAULT_SOCIETY = "default"
RETRY = '{"period_init_ms": 250, "period_max_ms": 500, "period_increase_factor": 2}'
"""Connecting to a robot that is not up yet (or not reachable) is retried every
half second at most."""

OPEN_TIMEOUT_MS = 1500
"""Milliseconds one attempt to open a link may take before it is given up and
retried. Zenoh's default, 10 s, bounds the TCP connect as well, and a connect
whose SYN was lost to a bad link waits for the kernel's resends (after 1 s, then
2 s, 4 s, ...) however long ago the link came back (2.8 s to reconnect
after 50 % loss cleared). Given up after 1.5 s (past the first resend), and
retried :data:`RETRY` 0.5 s later, an attempt goes out on the link at least
every second. A link that needs longer to open (a TLS handshake over a link of
300 ms round trips) needs a longer one: a ``--zenoh-config`` file's
``transport/unicast/open_timeout``."""

STUCK_LINK = 20
"""A link that cannot take a control message for a twentieth of the lease
is closed (Zenoh's ``wait_before_close``, 5 s by default; 100 ms with the
2 s lease), instead of stalling whoever sends to it.

Declarations (liveliness tokens, subscribers, interests) are sent with
congestion control *block*: a send to a link whose queue is full waits for
room, up to ``wait_before_close``, on the thread that sends it. In a router
that thread is the one reading the link the declaration came on: behind a
router, a robot declaring something while another robot's link was losing
half of its packets had its own link left unread for up to 5 s, and the
router dropped it past the lease, a healthy robot lost (2 of 4 trials of
``python -m benchmarks.link_loss``; none of 3 with 100 ms). Closed at once,
the stuck link's robot is lost, as it would be anyway, and connects again
when its link lets it; several sends may wait in a row before the close
takes hold, hence a small share of the lease."""

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
    plans: bool = False
    """The robot runs ``problem`` with the planner (``cfgplan run --robot``, not
    an emitted program): it says so with a token of its own, and may take over
    coordination (:func:`cfgplan.runtime.succession.candidates`)."""
    router: tuple[str, ...] = ()
    """Routers the robot is a Zenoh *client* of (``--router``): it connects to
    one of them and listens nowhere, and everything it says and hears goes
    through that router (connections that grow with the society, not with its
    square). With :attr:`keys`, the society's router (``cfgplan router --keys``),
    reached over TLS. Empty: a peer, linked to every robot it reaches."""

    def __post_init__(self) -> None:
        if not self.society:
            raise RunError("the society name is empty")
        for option, endpoints in (("--listen", self.listen), ("--connect", self.connect)):
            for endpoint in endpoints:
                problem = endpoint_problem(endpoint)
                if problem:
                    raise RunError(f"{option} {problem}", hint=ENDPOINT_HINT)
        for endpoint in self.router:
            problem = endpoint_problem(endpoint)
            if problem:
                raise RunError(f"--router {problem}", hint=ENDPOINT_HINT)
        if self.router and (self.listen or self.connect):
            given = "--listen" if self.listen else "--connect"
            raise RunError(
                f"--router and {given}: a client of a router reaches the others only through it",
                hint="give the router alone, or --listen/--connect without it (a mesh of peers)",
            )
        if self.lease is not None and not self.lease > 0:
            raise RunError(f"--lease {self.lease}: the lease must be a positive number of seconds")


RUNTIME_THREADS = "(acc: (worker_threads: 8), rx: (worker_threads: 4))"
"""Threads of Zenoh's runtimes (the ``ZENOH_RUNTIME`` environment variable): 8 to
accept links (Zenoh's default 1), 4 to read them (Zenoh's 2).

Zenoh sets ``SO_LINGER`` to 10 s on every TCP link (``TCP_LINGER_TIMEOUT`` in
``zenoh-link-tcp``, fixed when the wheel is built), so dropping a socket whose
FIN the other end has not acknowledged holds the dropping *thread* in
``close(2)`` until it is, or 10 s. A handshake with a robot behind a lossy
link that fails (it hangs up after its ``open_timeout``, or the router's
``accept_timeout`` runs out) is dropped on the accepting runtime, whose one
thread also drives the I/O of every link the listener accepted: while it
waits, the router (or a peer) reads none of its links and accepts none, and
past the lease drops them all, healthy robots lost. Sampled in a router
beside 50 % loss on one client's link, that thread sat in ``close(2)`` 6.9 to
14 s in the trials in which both healthy clients were dropped, as long as
their silence. With spare threads the stall ends sooner, not at once (an idle
thread takes the I/O over only once something wakes it; the lease's close of
the silent links does): a failed handshake on a dead link silenced the
healthy clients 1.8 s instead of 10 s (``tests/runtime/test_stuck_handshake.py``),
and they are still dropped once; the rest is Zenoh's to fix (its open report
"Zenoh should not use deprecated set_linger"). A lossy robot's
established link closed on a reading thread holds that one the same way,
hence spare readers too. A ``ZENOH_RUNTIME`` already set is kept."""


def spare_threads() -> None:
    """Give Zenoh's runtimes :data:`RUNTIME_THREADS` unless ``ZENOH_RUNTIME`` is set
    (read when Zenoh starts its first runtime: call before the first session)."""
    os.environ.setdefault("ZENOH_RUNTIME", RUNTIME_THREADS)


def load_zenoh() -> ModuleType:
    spare_threads()
    try:
        import zenoh
    except ImportError:
        raise RunError(
            "the Zenoh transport needs the eclipse-zenoh package, which is not installed",
            hint="pip install eclipse-zenoh",
        ) from None
    return zenoh


def reason(exc: BaseException) -> str:
    """Zenoh's message without the Rust source location it appends."""
    text = str(exc)
    inner = re.search(r'msg: "(.*?)"', text)
    if inner:
        text = inner.group(1)
    return re.sub(r" at \S+\.rs:\d+\.?", "", text).strip()


WAIT_BEFORE_CLOSE = "transport/link/tx/queue/congestion_control/block/wait_before_close"


def stuck_link_wait(lease_ms: int) -> str:
    """Microseconds (JSON5) a send waits on a full link before the link is
    closed, for a lease of ``lease_ms`` (:data:`STUCK_LINK`)."""
    return str(max(1, round(lease_ms * 1000 / STUCK_LINK)))


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
    settings, then the options; last, unless the file sets it, a stuck link is
    closed after a :data:`STUCK_LINK` th of the lease (:func:`follow_lease`).

    A file is read whole by Zenoh, which fills in its own default for every
    key the file leaves out; so a key whose value in the file is Zenoh's own
    default counts as not set, and gets cfgplan's (``--lease 10`` asks for
    Zenoh's 10 s lease)."""
    z = load_zenoh()
    config: zenoh.Config
    file_wait = None
    if options.config_file is not None:
        config = read_config(options.config_file)
        file_wait = config.get_json(WAIT_BEFORE_CLOSE)
        zenohs = z.Config()
        for key, value, what in DEFAULTS:
            if config.get_json(key) == zenohs.get_json(key):  # the file leaves it
                put_setting(config, key, value, what)
    else:
        config = z.Config()
        for key, value, what in DEFAULTS:
            put_setting(config, key, value, what)
    if options.router:
        put_setting(config, "mode", '"client"', "--router")
        put_setting(config, "connect/endpoints", json.dumps(list(options.router)), "--router")
        put_setting(config, "listen/endpoints", "[]", "--router (a client listens nowhere)")
        put_setting(config, "scouting/multicast/enabled", "false", "scouting")
    elif options.listen:
        put_setting(config, "listen/endpoints", json.dumps(list(options.listen)), "--listen")
    elif options.connect and config.get_json("listen/endpoints") == z.Config().get_json(
        "listen/endpoints"
    ):  # it reaches out; Zenoh's default would listen on every interface
        put_setting(config, "listen/endpoints", "[]", "--connect (listens nowhere)")
    if options.connect:
        put_setting(config, "connect/endpoints", json.dumps(list(options.connect)), "--connect")
    if options.listen or options.connect:
        put_setting(config, "scouting/multicast/enabled", "false", "scouting")
    if options.lease is not None:
        lease = str(max(1, round(options.lease * 1000)))
        put_setting(config, "transport/link/tx/lease", lease, "--lease")
    if file_wait is None or file_wait == z.Config().get_json(WAIT_BEFORE_CLOSE):
        follow_lease(config)  # the file leaves it
    if options.keys is not None:  # last: every endpoint, the file's too, becomes TLS
        from cfgplan.security.zenoh_tls import secure

        if robot is None:
            raise RunError("--keys: whose keys? (no robot named)")
        secure(config, options.keys, robot, options.society, put_setting)
    return config


def follow_lease(config: Any) -> None:
    """Set the wait before a stuck link is closed from ``config``'s lease
    (:data:`STUCK_LINK`): for a configuration whose file does not set it."""
    lease_ms = int(json.loads(config.get_json("transport/link/tx/lease")))
    put_setting(config, WAIT_BEFORE_CLOSE, stuck_link_wait(lease_ms), "the wait on a stuck link")


def read_config(path: str) -> zenoh.Config:
    """A Zenoh configuration file (JSON5), or a clear error."""
    z = load_zenoh()
    try:
        config: zenoh.Config = z.Config.from_file(path)
    except z.ZError as exc:
        raise RunError(f"cannot read the Zenoh configuration {path}: {reason(exc)}") from None
    return config


def put_setting(config: Any, key: str, value: str, option: str) -> None:
    """Set ``key`` to ``value`` (JSON5) on ``config``; Zenoh's refusal said as ``option``'s."""
    try:
        config.insert_json5(key, value)
    except Exception as exc:  # zenoh.ZError; zenoh is imported lazily
        raise RunError(f"{option}: Zenoh refuses {value}: {reason(exc)}") from None
