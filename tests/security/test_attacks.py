"""A society started with ``--keys``: its goal is served over TLS with mutual
authentication, and strangers and members beyond their rights get nothing in
(transport level).

Hermetic: loopback, free ports, scouting off, bounded waits, every process
stopped by its pid (:mod:`tests.runtime.netutil`). The attackers are plain
zenoh-python sessions in the test's process; those with a society certificate
are configured exactly as a robot program is (:func:`zenoh_config` with
``keys``). A negative ("nothing arrives") is trusted only next to a positive
over the same path: a member entitled to the data gets it in the same window,
or the attacker's own allowed message, sent after the forged one on the same
connection, arrives (Zenoh delivers one connection's reliable messages in order).
"""

from __future__ import annotations

import json
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import pytest

from cfgplan.runtime.zenoh_transport import ZenohOptions, zenoh_config
from cfgplan.security.keys import make_society, plan_society, write_society
from tests.backends.support import DOMAINS, EXAMPLE_IMPL, ROOT
from tests.runtime.netutil import (
    HERMETIC,
    Record,
    endpoint,
    first,
    free_port,
    hermetic_config,
    processes,
    read_trace,
    wait_for,
)

zenoh = pytest.importorskip("zenoh")

SOCIETY = "sec-test"
P = f"cfgplan/{SOCIETY}"
STEP2 = [
    str(DOMAINS / "cross-door/domain.lisp"),
    str(DOMAINS / "cross-door/state-6.2.2-step2.lisp"),
]
LIMIT = 90.0  # seconds: two interpreters, TLS handshakes and a run, on a loaded machine
QUIET = 3.0  # seconds an attacker listens for what it must not get


def _keys(folder: Path, society: str = SOCIETY) -> Path:
    """Emil coordinates (he owns step 2's goal); Eve is a robot of the society
    too, the console an operator tool."""
    plan = plan_society(society, ["Emil", "Pippi", "Eve"], ["console"], ["Emil"])
    write_society(folder, make_society(plan), force=False)
    return folder


class Inbox:
    """What a session's subscribers received, by key expression, thread-safe."""

    def __init__(self) -> None:
        self.got: list[tuple[str, bytes]] = []
        self._lock = threading.Lock()
        self._event = threading.Event()

    def __call__(self, sample: Any) -> None:
        with self._lock:
            self.got.append((str(sample.key_expr), sample.payload.to_bytes()))
        self._event.set()

    def names(self) -> list[str]:
        with self._lock:
            return [k for k, _ in self.got]

    def wait(self, match: Callable[[str], bool], limit: float) -> bool:
        deadline = time.monotonic() + limit
        while time.monotonic() < deadline:
            if any(match(k) for k in self.names()):
                return True
            self._event.wait(0.05)
            self._event.clear()
        return False


@contextmanager
def session(config: Any) -> Iterator[Any]:
    opened = zenoh.open(config)
    try:
        yield opened
    finally:
        opened.close()


def member(
    keys: Path, name: str, listen: tuple[str, ...] = (), connect: tuple[str, ...] = ()
) -> Any:
    """A session with ``name``'s certificate, configured as a robot program's is."""
    folder = keys.parent
    hermetic = str(hermetic_config(folder))
    options = ZenohOptions(SOCIETY, listen, connect, hermetic, keys=str(keys))
    return zenoh_config(options, name)


def stranger(connect: str, tls: dict[str, object] | None = None) -> Any:
    """A plain zenoh-python peer: no certificate, or the given TLS settings."""
    config = zenoh.Config.from_json5(HERMETIC)
    config.insert_json5("mode", '"peer"')
    config.insert_json5("connect/endpoints", json.dumps([connect]))
    config.insert_json5("listen/endpoints", "[]")
    for key, value in (tls or {}).items():
        config.insert_json5(f"transport/link/tls/{key}", json.dumps(value))
    return config


def _robot(
    running: Any, folder: Path, name: str, network: list[str], *extra: str
) -> tuple[Any, Path]:
    trace = folder / f"{name.lower()}.jsonl"
    args = ["-m", "cfgplan", "run", *STEP2, "--robot", name, "--impl", str(EXAMPLE_IMPL)]
    args += ["--rate", "20", "--trace", str(trace), *network, *extra]
    return running.start(args, folder / f"{name.lower()}.log"), trace


@pytest.mark.slow
def test_a_keyed_society_serves_its_goal_and_strangers_read_nothing(tmp_path: Path) -> None:
    """Emil (cfgplan run) and Pippi (her emitted program), each its own process
    with --keys, cross the door over TLS
    (tcp/ endpoints taken as tls/), and switch 44 -> 47 when Emil's compass fails
    (the coordinator's prepare and commit, Pippi's acknowledgements); meanwhile
    a peer without a certificate and one with a certificate of another CA (same
    society name, same robot names) connect to Emil's endpoint and receive
    nothing, not even a liveliness token, while the society's operator console
    receives channel values."""
    keys = _keys(tmp_path / "keys")
    rival = _keys(tmp_path / "rival-keys")  # another CA, the same names
    port = free_port()
    common = ["--zenoh-config", str(hermetic_config(tmp_path)), "--lease", "1", "--keys", str(keys)]
    with processes() as running:
        emil, emil_trace = _robot(
            running,
            tmp_path,
            "Emil",
            ["--listen", endpoint(port), *common],
            "--cycles",
            "240",
            "--inject",
            "fail compass(Emil) at cycle 120",
        )
        emitted = tmp_path / "emitted"  # Pippi runs her emitted program
        made = subprocess.run(
            [
                sys.executable,
                "-m",
                "cfgplan",
                "emit",
                *STEP2,
                "--lang",
                "python",
                "-o",
                str(emitted),
            ],
            cwd=ROOT,
            capture_output=True,
            text=True,
            timeout=LIMIT,
        )
        assert made.returncode == 0, made.stderr
        program = [str(emitted / "pippi.py"), "--impl", str(EXAMPLE_IMPL), "--rate", "20"]
        program += ["--listen", endpoint(free_port()), "--connect", endpoint(port), *common]
        pippi = running.start([*program, "--duration", "90"], tmp_path / "pippi.log")
        wait_for("Emil sees Pippi", first(emil_trace, lambda r: r["event"] == "robot-seen"), LIMIT)
        inboxes = {}
        tls_of_rival = {
            "root_ca_certificate": str(rival / "ca.pem"),
            "connect_private_key": str(rival / "eve.key"),
            "connect_certificate": str(rival / "eve.pem"),
            "verify_name_on_connect": False,
        }
        with (
            session(stranger(endpoint(port))) as plain,
            session(stranger(f"tls/127.0.0.1:{port}", tls_of_rival)) as forger,
            session(member(keys, "console", connect=(f"tls/127.0.0.1:{port}",))) as console,
        ):
            for name, attacker in (("plain", plain), ("rival", forger), ("console", console)):
                inbox = inboxes[name] = Inbox()
                attacker.declare_subscriber(f"{P}/**", inbox)
                attacker.liveliness().declare_subscriber(f"{P}/*/alive", inbox, history=True)
            assert inboxes["console"].wait(lambda k: "/ch/" in k, LIMIT), "the console got nothing"
            time.sleep(QUIET)
            assert inboxes["plain"].names() == [], "a peer without a certificate read the society"
            assert inboxes["rival"].names() == [], "a peer of another CA read the society"
            assert f"{P}/Emil/alive" in inboxes["console"].names()
        assert emil.wait(LIMIT) == 0
        assert pippi.poll() in (None, 0)  # stopped by its pid when the test ends
    mine = read_trace(emil_trace)
    crossing = [r for r in mine if r["event"] == "call" and r["functionality"] == "cross-door"]
    ran = [c for c in crossing if c["status"] == "ran"]
    assert len(ran) >= len(crossing) // 2 > 0, "the goal was not served over TLS"
    # the switch protocol passes the access control: prepare, commit, acknowledgements
    (switch,) = [r for r in mine if r["event"] == "switch"]
    assert (switch["from_cost"], switch["to_cost"]) == (44, 47)
    assert [c for c in ran if int(c["cycle"]) > int(switch["cycle"]) + 3]  # type: ignore[call-overload]
    assert (tmp_path / "emil.log").read_text().count("Traceback") == 0


@pytest.mark.slow
def test_members_beyond_their_rights_get_nothing_through(tmp_path: Path) -> None:
    """Access control by certificate name, with the configuration robot programs
    use. Eve, a robot of the society but not its coordinator, cannot send Pippi
    a switch (configure), declare Pippi's liveliness token, or read Pippi's
    channels or the coordinator's reports; the operator console cannot put a
    value on a channel nor send a switch. Emil, the coordinator, can send Pippi
    a switch; Eve can put on Pippi's channels (see the next test)."""
    keys = _keys(tmp_path / "keys")
    where, emils = f"tls/127.0.0.1:{free_port()}", f"tls/127.0.0.1:{free_port()}"
    pippi_in, eve_in, seen = Inbox(), Inbox(), Inbox()
    with session(member(keys, "Pippi", listen=(where,))) as pippi:
        for key in (f"{P}/Pippi/ch/**", f"{P}/Pippi/configure", f"{P}/coordinator/*"):
            pippi.declare_subscriber(key, pippi_in)
        pippi.liveliness().declare_subscriber(f"{P}/*/alive", seen, history=True)
        with (
            session(member(keys, "Emil", (emils,), (where,))) as emil,
            session(member(keys, "Eve", connect=(where, emils))) as eve,
            session(member(keys, "console", connect=(where,))) as console,
        ):
            eve.declare_subscriber(f"{P}/Pippi/**", eve_in)
            eve.declare_subscriber(f"{P}/coordinator/*", eve_in)
            token = eve.liveliness().declare_token(f"{P}/Eve/alive")
            forged = eve.liveliness().declare_token(f"{P}/Emil/alive")
            assert seen.wait(lambda k: k == f"{P}/Eve/alive", LIMIT), "Eve never joined"
            # forged first, then an allowed message on the same connection
            console.put(f"{P}/Pippi/ch/Emil/F7/F3/pos/Pippi/Door1", b"[666, 666]")
            console.put(f"{P}/Pippi/configure", b"forged by the console")
            eve.put(f"{P}/Pippi/configure", b'{"kind": "commit", "forged": true}')
            eve.put(f"{P}/Pippi/ch/Eve/F1/F2/x", b"Eve's channel value")  # a robot may
            emil.put(f"{P}/Pippi/configure", b"Emil's commit")
            emil.put(f"{P}/Pippi/ch/Emil/F9/F3/y", b"Emil's channel value")
            assert pippi_in.wait(lambda k: k == f"{P}/Pippi/ch/Emil/F9/F3/y", LIMIT)
            assert pippi_in.wait(lambda k: k == f"{P}/Pippi/ch/Eve/F1/F2/x", LIMIT)
            assert pippi_in.wait(lambda k: k == f"{P}/Pippi/configure", LIMIT)
            time.sleep(1.0)  # and a margin for the console's connection
            payloads = [p for _, p in pippi_in.got]
            assert b"Emil's commit" in payloads and b"Eve's channel value" in payloads
            assert not [p for p in payloads if b"forged" in p or p == b"[666, 666]"]
            assert f"{P}/Emil/alive" not in seen.names()
            theirs = [p for _, p in eve_in.got if b"Eve" not in p and b"forged" not in p]
            assert theirs == [], "Eve read what Emil sent Pippi"  # (her own puts come back)
            token.undeclare()
            forged.undeclare()


@pytest.mark.slow
def test_a_robot_cannot_forge_a_value_on_another_robots_channel(tmp_path: Path) -> None:
    """Eve, a robot of the society, puts a forged door position on the channel
    key Emil's cross-door reads, naming Pippi as its sender (as Pippi sends
    it): the access control drops it, since a channel key names its sender
    (:mod:`cfgplan.runtime.keys`). Under her own name it would reach nobody:
    Emil's channel listens to the key naming Pippi. Nor can she report to
    the coordinator in Pippi's name: each robot has its own key to it."""
    keys = _keys(tmp_path / "keys")
    where = f"tls/127.0.0.1:{free_port()}"
    emil_in = Inbox()
    with session(member(keys, "Emil", listen=(where,))) as emil:
        emil.declare_subscriber(f"{P}/Emil/ch/**", emil_in)
        emil.declare_subscriber(f"{P}/coordinator/*", emil_in)
        with session(member(keys, "Eve", connect=(where,))) as eve:
            time.sleep(1.0)  # the subscriptions reach Eve
            eve.put(f"{P}/Emil/ch/Pippi/F7/F3/pos/Emil/Door1", b"[666, 666]")
            eve.put(f"{P}/coordinator/Pippi", b"Eve's report as Pippi")
            eve.put(f"{P}/coordinator/Eve", b"Eve's own report")
            assert emil_in.wait(lambda k: k == f"{P}/coordinator/Eve", LIMIT)
            time.sleep(0.5)
            got = [p for _, p in emil_in.got]
            assert b"[666, 666]" not in got and b"Eve's report as Pippi" not in got


@pytest.mark.slow
def test_a_member_says_nothing_of_what_is_not_its_own(tmp_path: Path) -> None:
    """A process holding only Pippi's key (a compromised robot) tells the
    coordinator Emil, on Pippi's own key and in her name, that (camera Emil)
    and (compass Emil) are gone and that compass(Emil) failed, and puts on her
    own channel to Emil a value whose envelope says it is from Mallory. Emil
    drops all three and says so, and his run goes on to its end, exit 0
    (before: the fact removal stopped the society, exit 3; the failure
    switched it; the value was taken and traced as Mallory's)."""
    keys = _keys(tmp_path / "keys")
    port = free_port()
    common = ["--zenoh-config", str(hermetic_config(tmp_path)), "--lease", "1", "--keys", str(keys)]
    with processes() as running:
        emil, emil_trace = _robot(
            running, tmp_path, "Emil", ["--listen", endpoint(port), *common], "--cycles", "300"
        )
        hers = free_port()
        network = ["--listen", endpoint(hers), "--connect", endpoint(port), *common]
        _robot(running, tmp_path, "Pippi", network, "--duration", "90")
        wait_for("Emil sees Pippi", first(emil_trace, lambda r: r["event"] == "robot-seen"), LIMIT)
        at = f"tls/127.0.0.1:{port}"
        with (  # the console hears what Pippi puts at her end (peers do not route)
            session(member(keys, "console", connect=(f"tls/127.0.0.1:{hers}",))) as console,
            session(member(keys, "Pippi", connect=(at,))) as forger,
        ):
            inbox = Inbox()
            console.declare_subscriber(f"{P}/Emil/ch/Pippi/**", inbox)
            assert inbox.wait(lambda k: True, LIMIT), "Pippi sends Emil nothing"
            channel = inbox.names()[0]
            now = time.time()
            for detection in (
                {"kind": "facts", "robot": "Pippi", "t": now, "how": "operator",
                 "removed": [["camera", "Emil"], ["compass", "Emil"]]},
                {"kind": "failure", "robot": "Pippi", "t": now, "instance": ["compass", "Emil"],
                 "how": "reported"},
            ):  # fmt: skip
                report = {"type": "report", "robot": "Pippi", "detection": detection}
                forger.put(f"{P}/coordinator/Pippi", json.dumps(report).encode())
            lie = {"from": "Mallory", "seq": 10**6, "t": now, "period": 0.05, "value": [99, 99]}
            forger.put(channel, json.dumps(lie).encode())

            def said(text: str) -> Callable[[], Record | None]:
                return first(emil_trace, lambda r: r["event"] == "error" and text in str(r))

            wait_for("the state update refused", said("Pippi reported a state update"), LIMIT)
            wait_for("the failure refused", said("failure of compass(Emil), which does"), LIMIT)
            wait_for("the forged sender refused", said("says it is from 'Mallory'"), LIMIT)
        assert emil.wait(LIMIT) == 0, (tmp_path / "emil.log").read_text()
    mine = read_trace(emil_trace)
    assert [r for r in mine if r["event"] in ("facts", "switch", "failure")] == []
    assert not [r for r in mine if r["event"] == "receive" and r.get("from") == "Mallory"]
    crossing = [r for r in mine if r["event"] == "call" and r["functionality"] == "cross-door"]
    assert crossing and crossing[-1]["status"] == "ran"
