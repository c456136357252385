"""A Zenoh router for a society whose robots are its clients (``cfgplan router``).

In a mesh of peers (``--listen``/``--connect``) every robot holds a link to
every other: N·(N−1)/2 connections, and an idle traffic of keep-alives and
liveliness that grows with the square of the society. Zenoh's answer at
scale is the router: each robot is a *client* (``cfgplan run --router
ENDPOINT``) holding one link, to the router, which forwards what each says
to whoever subscribed; connections and idle traffic grow with N.

This is Zenoh's own router — the ``router`` mode of the Zenoh library's
session, the same code as ``zenohd`` — opened with cfgplan's lease, so a
robot that freezes is reported lost after the lease as among peers, and
scouting off (nothing is found but the clients that connect). ``zenohd``,
or ROS 2's ``rmw_zenohd``, serve the robots as well: ``--router`` names any
of them.

**With the society's keys** (``--keys DIR``, the router's own key and
certificate that ``cfgplan keys new`` makes, :mod:`cfgplan.security.zenoh_tls`)
the router listens on TLS only and asks every client for a certificate of the
society's authority (mutual authentication: a client without one cannot open
a session), and enforces the society's access control on every client, by
the name its certificate carries: what a robot may put, declare and
subscribe to, and what it may be sent, as the robots enforce among peers.
So a robot that puts on another's keys, declares another's liveliness token
or subscribes to others' channels is refused by the router itself; nothing
of it reaches the others. The robots still hold the router to the same
rules, mirrored, and check everything it forwards (a router is trusted with
who sent what, not with what it says).

What a router costs: one process every message crosses (one hop more on
loopback: tens of microseconds) and that the society needs. A router that
ends cuts every robot off from every other — each sees every other lost and,
following its coordinator, stops its part (``--without-coordinator``) —
until it runs again on the same endpoint: the clients reconnect by
themselves, and the coordinator takes its society back
(``cfgplan launch --respawn`` starts it again).
"""

from __future__ import annotations

import json
import signal
import threading
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from types import FrameType
from typing import Any

from cfgplan.runtime.errors import RunError
from cfgplan.runtime.zenoh_config import (
    DEFAULT_LEASE,
    ENDPOINT_HINT,
    WAIT_BEFORE_CLOSE,
    endpoint_problem,
    follow_lease,
    load_zenoh,
    put_setting,
    read_config,
    reason,
)

__all__ = ["DEFAULT_LISTEN", "RouterOptions", "listening", "router_config", "serve"]

DEFAULT_LISTEN = "tcp/[::]:7447"
"""Where a router listens unless told: Zenoh's port on every interface, as ``zenohd``."""


@dataclass(frozen=True)
class RouterOptions:
    """How a router is reached and how soon it gives a silent client up."""

    listen: tuple[str, ...] = (DEFAULT_LISTEN,)
    lease: float = DEFAULT_LEASE
    """Seconds without a word after which a client is dropped (its tokens go:
    the others see it lost), as a robot's ``--lease``."""
    config_file: str | None = None
    """A Zenoh configuration file under the options (``--zenoh-config``)."""
    keys: str | None = None
    """A folder of the society's keys with the router's (``--keys``): TLS, mutual
    authentication and the society's access control on every client."""

    def __post_init__(self) -> None:
        if not self.listen:
            raise RunError("a router must listen somewhere", hint=ENDPOINT_HINT)
        for endpoint in self.listen:
            problem = endpoint_problem(endpoint)
            if problem:
                raise RunError(f"--listen {problem}", hint=ENDPOINT_HINT)
        if not self.lease > 0:
            raise RunError(f"--lease {self.lease}: the lease must be a positive number of seconds")


def router_config(options: RouterOptions) -> Any:
    """The Zenoh configuration of a router: a file's (if any), then router
    mode, the endpoints it listens on, no multicast scouting and the lease;
    unless the file sets it, a client's link that stays full is closed after a
    small share of the lease (:data:`~cfgplan.runtime.zenoh_config.STUCK_LINK`):
    the router sends a client declarations on the thread that reads the link
    they came on, and a client behind a lossy link would stall that link (a
    healthy robot's) for up to Zenoh's 5 s, past its lease; with keys, last, its
    certificate and the society's access control (every endpoint TLS)."""
    zenohs = load_zenoh().Config()
    config = zenohs if options.config_file is None else read_config(options.config_file)
    leaves_wait = config.get_json(WAIT_BEFORE_CLOSE) == zenohs.get_json(WAIT_BEFORE_CLOSE)
    settings = (
        ("mode", '"router"', "router mode"),
        ("listen/endpoints", json.dumps(list(options.listen)), "--listen"),
        ("scouting/multicast/enabled", "false", "scouting"),
        ("transport/link/tx/lease", str(max(1, round(options.lease * 1000))), "--lease"),
    )
    for key, value, what in settings:
        put_setting(config, key, value, what)
    if leaves_wait:
        follow_lease(config)
    if options.keys is not None:
        from cfgplan.security.zenoh_tls import router_of, secure, society_of

        me, society = router_of(options.keys), society_of(options.keys).society
        secure(config, options.keys, me.name, society, put_setting)
    return config


def listening(options: RouterOptions) -> list[str]:
    """The endpoints the router listens on, as its configuration has them (with
    keys: TLS)."""
    if options.keys is None:
        return list(options.listen)
    from cfgplan.security.zenoh_tls import secure_endpoint

    return [secure_endpoint(e) for e in options.listen]


def serve(
    options: RouterOptions,
    say: Callable[[str], None],
    stop: threading.Event | None = None,
) -> None:
    """Run a router until ``stop`` is set, or SIGINT or SIGTERM (on the main
    thread): ``say`` is told where it listens, and when it stops."""
    z = load_zenoh()
    stop = stop or threading.Event()
    try:
        session = z.open(router_config(options))
    except z.ZError as exc:
        raise RunError(f"the router cannot open: {reason(exc)}", hint=ENDPOINT_HINT) from None
    previous: dict[int, Any] = {}
    if threading.current_thread() is threading.main_thread():

        def handler(signum: int, frame: FrameType | None) -> None:
            stop.set()

        for signum in (signal.SIGINT, signal.SIGTERM):
            previous[signum] = signal.signal(signum, handler)
    try:
        said = f"router {session.info.zid()} listening on {_joined(listening(options))}"
        if options.keys is not None:
            from cfgplan.security.zenoh_tls import router_of

            said += f" (keys of {router_of(options.keys).common_name})"
        say(said)
        while not stop.wait(0.5):
            pass
        say("router stopped")
    finally:
        session.close()
        for number, was in previous.items():
            signal.signal(number, was)


def _joined(endpoints: Sequence[str]) -> str:
    return ", ".join(endpoints)
