"""A robot's Zenoh session with its society's keys: TLS, mutual authentication,
access control by certificate name (``--keys DIR``).

From a folder made by ``cfgplan keys new`` (:mod:`cfgplan.security.keys`)
and the name of a robot (or operator tool), :func:`secure_settings` gives the
settings put on top of the session's configuration
(:func:`cfgplan.runtime.zenoh_config.zenoh_config`), with the keys of the
Zenoh configuration schema (``DEFAULT_CONFIG.json5`` of eclipse-zenoh,
``transport/link/tls`` and ``access_control``; checked against the installed
eclipse-zenoh by tests/security/test_zenoh_tls.py):

* **TLS with mutual authentication**: the society's CA is the only root
  (``root_ca_certificate``), the member's certificate and key serve both when
  it listens and when it connects, ``enable_mtls`` makes the listening side
  ask for the connecting side's certificate. A peer without a certificate of
  the society's CA cannot open a session at all: the TLS handshake fails.
  ``verify_name_on_connect`` is off: a robot's certificate names the robot,
  not a host (robots move between networks), and what a peer may do is
  decided by its certificate's name below, not by the address it is reached at.
  ``close_link_on_expiration``: a connection ends when a certificate expires.
* **Endpoints**: with keys every endpoint is TLS: ``tcp/HOST:PORT`` becomes
  ``tls/HOST:PORT`` (so the same ``--listen``/``--connect`` work with and
  without keys), ``tls/`` and ``quic/`` stay, any other protocol is refused;
  Zenoh's own default listener (``tcp/[::]:0``) becomes ``tls/[::]:0``.
* **Access control of least privilege** (``access_control``, default
  ``deny``), the same rules in every member's configuration: each robot
  enforces them on what it receives (``ingress``) and sends (``egress``),
  per peer, the peer named by its certificate's common name
  (``cert_common_names``, :func:`cfgplan.security.keys.common_name`; only
  the names ``society.json`` lists: a renewed member's old certificate is
  nobody, :mod:`cfgplan.security.renew`).
  With ``P`` = ``cfgplan/<society>`` (:mod:`cfgplan.runtime.keys`), a robot R may

  - put on ``P/*/ch/R/**`` (the global channels it sends on: the keys that
    name it as their sender) and ``P/coordinator/R`` (its own key to the
    coordinator: no robot can speak there in another's name)
    (its reports and acknowledgements, 5.5); a coordinator also on
    ``P/*/configure`` (prepare, commit, abort, finish): no other robot can
    send a robot the steps of a switch;
  - declare only its own liveliness tokens ``P/R/alive``, ``P/R/process/*``
    (one per process of R) and ``P/R/problem/**`` (the problem it runs,
    :mod:`cfgplan.security.identity`);
  - subscribe only to its own channels ``P/R/ch/**`` and ``P/R/configure``
    (a coordinator also to ``P/coordinator/*``), and watch ``P/*/alive``,
    ``P/*/process/*`` and ``P/*/problem/**``;
  - be sent only those (egress): another robot's channels and switches, and
    the reports of the others, are not sent to it even when it asks.

  An operator tool may watch and read everything under ``P`` and publish nothing.

* **Behind the society's router** (``cfgplan router --keys``, ``--router``
  with ``--keys``; its certificate's common name is ``<society>/router/<name>``,
  :func:`router_of`): every robot and tool is a client of the router, which
  holds each of them, by its certificate's name, to the rules above (its
  session has the members' policies and none of its own: routers do not
  link to each other). Each member holds the router, in turn, to its own
  rules :func:`mirrored` (:func:`access_control` with ``me``): the router may
  send Pippi only what Pippi may be sent, and Pippi sends it only what she
  may send. The router is trusted with one thing the robots cannot check:
  that a message it forwards on a key naming Emil came from Emil's
  certificate; what the message says, the robots check as among peers.

A channel's key names its receiver *and its sender*
(``P/<receiver>/ch/<sender>/<source>/<target>/<data>``,
:mod:`cfgplan.runtime.keys`), and a receiver listens only to the key naming
the robot it expects data from: so no robot of the society can pass a value
off as another's, though which robot sends into which channel changes with
every switch while these rules are fixed when the session opens. What the
rules cannot say is which robot is the coordinator of the current goal:
every robot ``cfgplan keys new`` marked as a coordinator (by default the
robots a goal of the state names) may send switches.
"""

from __future__ import annotations

import json
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

from cfgplan.key_chunks import PREFIX, chunk
from cfgplan.run_errors import RunError
from cfgplan.security.keys import CA_STEM, Member, SocietyKeys, read_society

__all__ = [
    "SECURE_PROTOCOLS",
    "access_control",
    "member_of",
    "member_rules",
    "mirrored",
    "router_of",
    "secure",
    "secure_endpoint",
    "secure_settings",
    "society_for",
    "society_of",
]

SECURE_PROTOCOLS = ("tls", "quic")
"""Protocols of Zenoh links that carry the certificates."""

_PROTOCOL = re.compile(r"^([A-Za-z0-9+.-]+)/(.*)$", re.DOTALL)


def secure_endpoint(endpoint: str) -> str:
    """``tcp/HOST:PORT`` as ``tls/HOST:PORT``; ``tls/`` and ``quic/`` as they are;
    :class:`RunError` for any other protocol (it would carry no certificate)."""
    match = _PROTOCOL.match(endpoint)
    protocol = match.group(1).lower() if match else ""
    if match and protocol == "tcp":
        return f"tls/{match.group(2)}"
    if protocol in SECURE_PROTOCOLS:
        return endpoint
    raise RunError(
        f"{endpoint!r}: with --keys every endpoint is TLS (tcp/ is taken as tls/); "
        f"{protocol or 'this'} carries no certificate",
        hint="give tls/HOST:PORT or tcp/HOST:PORT",
    )


def society_of(folder: str | Path) -> SocietyKeys:
    """The society a keys folder is for (its ``society.json``)."""
    return read_society(Path(folder))


def member_of(keys: SocietyKeys, name: str, folder: Path) -> Member:
    """The member ``name`` (a robot, else an operator tool, else a router) of
    ``keys``, with its files in ``folder``; :class:`RunError` naming what is missing."""
    member = keys.named(name)
    if member is None:
        robots = ", ".join(m.name for m in keys.robots)
        raise RunError(
            f"{folder} has no certificate for {name} (society {keys.society}: {robots})",
            hint=f"make the society's keys with --robot {name}",
        )
    for path in (folder / f"{CA_STEM}.pem", folder / f"{member.stem}.pem"):
        if not path.is_file():
            raise RunError(f"{path} not found (copy it from where the society's keys were made)")
    key = folder / f"{member.stem}.key"
    if not key.is_file():
        raise RunError(f"{key} not found: {name}'s private key")
    if key.stat().st_mode & 0o077:
        raise RunError(
            f"{key} can be read by others; a private key must be readable by its owner only",
            hint=f"chmod 600 {key}",
        )
    return member


Rule = tuple[str, tuple[str, ...], tuple[str, ...]]
"""One permission: (flow, messages, key expressions)."""

WATCH = ("declare_liveliness_subscriber", "liveliness_query")


def member_rules(society: str, member: Member) -> list[Rule]:
    """What ``member`` (a robot or an operator tool) may send (``ingress``: what
    whoever it is linked to takes from it) and be sent (``egress``)."""
    p = f"{PREFIX}/{chunk(society)}"
    alive = (f"{p}/*/alive", f"{p}/*/process/*", f"{p}/*/problem/**")  # tokens: who runs,
    # which process of it, and which problem
    if member.kind == "operator":
        return [
            ("ingress", ("declare_subscriber",), (f"{p}/**",)),
            ("ingress", WATCH, alive),
            ("egress", ("put",), (f"{p}/**",)),
            ("egress", ("liveliness_token", "reply"), alive),
        ]
    r = f"{p}/{chunk(member.name)}"
    puts: tuple[str, ...] = (
        f"{p}/*/ch/{chunk(member.name)}/**",
        f"{p}/coordinator/{chunk(member.name)}",
    )
    reads: tuple[str, ...] = (f"{r}/ch/**", f"{r}/configure")
    if member.coordinator:
        puts += (f"{p}/*/configure",)
        reads += (f"{p}/coordinator/*",)
    return [
        ("ingress", ("put",), puts),
        ("ingress", ("declare_subscriber",), reads),
        ("ingress", ("liveliness_token",), (f"{r}/alive", f"{r}/process/*", f"{r}/problem/**")),
        ("ingress", (*WATCH, "reply"), alive),
        ("egress", ("put",), reads),
        ("egress", ("declare_subscriber",), (f"{p}/**",)),
        ("egress", ("liveliness_token", *WATCH, "reply"), alive),
    ]


def mirrored(rules: list[Rule]) -> list[Rule]:
    """``rules`` seen from the other end of the link: what one side may send is
    what the other may be sent."""
    swap = {"ingress": "egress", "egress": "ingress"}
    return [(swap[flow], messages, keys) for flow, messages, keys in rules]


def access_control(keys: SocietyKeys, me: Member | None = None) -> dict[str, Any]:
    """Zenoh's ``access_control`` in the session of ``me`` (see the module
    docstring): deny by default, then per robot and operator tool what it may
    send and be sent; and, in a robot's or a tool's own session, per router of
    the society, what ``me`` may send it and be sent by it — its own rules
    :func:`mirrored`. A router is held to nothing else: the society's routers
    do not link to each other."""
    rules: list[dict[str, Any]] = []
    subjects: list[dict[str, Any]] = []
    policies: list[dict[str, Any]] = []

    def policy(member: Member, allowed: list[Rule]) -> None:
        ids = []
        for flow, messages, key_exprs in allowed:
            ids.append(f"r{len(rules)}")
            rules.append(
                {
                    "id": ids[-1],
                    "messages": list(messages),
                    "flows": [flow],
                    "permission": "allow",
                    "key_exprs": list(key_exprs),
                }
            )
        subject = f"s{len(subjects)}"
        subjects.append({"id": subject, "cert_common_names": [member.common_name]})
        policies.append({"id": f"p{len(policies)}", "rules": ids, "subjects": [subject]})

    for member in keys.members:
        if member.kind != "router":
            policy(member, member_rules(keys.society, member))
    if me is not None and me.kind != "router":
        for router in keys.routers:
            policy(router, mirrored(member_rules(keys.society, me)))
    return {
        "enabled": True,
        "default_permission": "deny",
        "rules": rules,
        "subjects": subjects,
        "policies": policies,
    }


def secure_settings(folder: str | Path, name: str, society: str) -> list[tuple[str, str, str]]:
    """The settings of ``name``'s session (a robot's, a tool's or the router's)
    with the keys in ``folder``, as
    (key, JSON5 value, what) for :meth:`zenoh.Config.insert_json5`; the
    endpoints are made secure by :func:`secure_endpoint` apart from these."""
    where = Path(folder)
    keys = society_of(where)
    if keys.society != society:
        raise RunError(
            f"--society {society}, but the keys in {where} are for society {keys.society}",
            hint=f"give --society {keys.society}, or leave --society out",
        )
    member = member_of(keys, name, where)
    tls = {
        "root_ca_certificate": str((where / f"{CA_STEM}.pem").resolve()),
        "listen_private_key": str((where / f"{member.stem}.key").resolve()),
        "listen_certificate": str((where / f"{member.stem}.pem").resolve()),
        "enable_mtls": True,
        "connect_private_key": str((where / f"{member.stem}.key").resolve()),
        "connect_certificate": str((where / f"{member.stem}.pem").resolve()),
        "verify_name_on_connect": False,
        "close_link_on_expiration": True,
    }
    return [
        *((f"transport/link/tls/{k}", json.dumps(v), "--keys") for k, v in tls.items()),
        ("access_control", json.dumps(access_control(keys, member)), "--keys (access control)"),
    ]


Setter = Callable[[Any, str, str, str], None]
"""How a setting goes into a Zenoh configuration: (config, key, JSON5, what)."""


def _secured(value: Any) -> Any:
    """A configuration's endpoints (a list, or lists per mode) made secure."""
    if isinstance(value, dict):
        return {mode: _secured(endpoints) for mode, endpoints in value.items()}
    if isinstance(value, list):
        return [secure_endpoint(str(e)) for e in value]
    return value


def secure(config: Any, folder: str, name: str, society: str, put: Setter) -> None:
    """Put ``name``'s keys from ``folder`` on ``config`` (:func:`secure_settings`)
    and make every listen and connect endpoint it has TLS (:func:`secure_endpoint`)."""
    for key, value, what in secure_settings(folder, name, society):
        put(config, key, value, what)
    for key in ("listen/endpoints", "connect/endpoints"):
        endpoints = json.loads(config.get_json(key))
        put(config, key, json.dumps(_secured(endpoints)), f"--keys ({key})")


def router_of(folder: str | Path) -> Member:
    """The society's router whose keys are in ``folder`` (``cfgplan keys new``
    makes one); :class:`RunError` when its keys have none, or several."""
    keys = society_of(folder)
    if len(keys.routers) == 1:
        return keys.routers[0]
    if not keys.routers:
        raise RunError(
            f"{folder} has no certificate for a router (keys made before routers had their own)",
            hint="make the society's keys again with cfgplan keys new (it makes the "
            "router's), or connect the robots as peers (--topology mesh, --listen/--connect)",
        )
    names = ", ".join(m.name for m in keys.routers)
    raise RunError(f"{folder} has the keys of several routers ({names}); a society has one")


def society_for(folder: str | None, society: str, default: str) -> str:
    """The society of a run: ``society`` as given, or with ``folder`` of keys and
    ``society`` left at ``default``, the keys' society."""
    if folder is None or society != default:
        return society
    return society_of(folder).society
