"""The society's secured router (``cfgplan router --keys``, ``cfgplan launch
--keys``): the robots are its clients over TLS with mutual authentication, and
the router enforces the society's access control on each of them.

A launch with keys plans and runs through the router (one connection per
robot, to the router); a client without a certificate of the society's
authority cannot open a session with the router, and a member with a valid
certificate that puts or declares beyond its rights is refused by the router
itself (the receiving robot's own access control would let it in); a frozen
router and a killed one cost the society its links, and it serves its goal
again once the router is back.

Hermetic: loopback, free ports, scouting off, bounded waits, every process
stopped by its pid (:mod:`tests.runtime.netutil`; a launch's by
:func:`tests.cli.test_launch._launch` and its pids).
"""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import threading
import time
from pathlib import Path
from typing import Any

import pytest

from cfgplan.runtime.zenoh_transport import ZenohOptions, zenoh_config
from tests.backends.support import EXAMPLE_IMPL
from tests.cli.test_launch import (
    LIMIT,
    _follow,
    _gone,
    _launch,
    _pids,
    cross_door_served,
    society_keys,
)
from tests.runtime.netutil import (
    endpoint,
    free_port,
    hermetic_config,
    processes,
    read_trace,
    wait_for,
)
from tests.security.test_attacks import Inbox, session, stranger

zenoh = pytest.importorskip("zenoh")

SOCIETY = "routed"
P = f"cfgplan/{SOCIETY}"
QUIET = 3.0  # seconds a subscriber listens for what must not arrive
FREEZE = 4.0  # seconds the router is frozen: past the robots' lease of 1 s


def _keys(folder: Path) -> Path:
    """Emil coordinates step 2 of cross-door, Pippi helps, Eve is a robot of the
    society too; the router has its own key."""
    return society_keys(folder, SOCIETY, "Emil", "Pippi", "Eve")


def _ended(launched: subprocess.Popen[str], lines: list[str], reader: threading.Thread) -> str:
    """The whole output of a launch that ended (exit status 0), or was killed (a failure)."""
    if launched.poll() is None:
        launched.kill()
    reader.join(10.0)
    out, err = "".join(lines), launched.stderr.read() if launched.stderr else ""
    assert launched.wait(10.0) == 0, f"{out}\n{err}"
    assert "Traceback" not in out + err
    return out + err


@pytest.mark.slow
def test_a_launch_with_keys_plans_and_runs_through_the_secured_router(tmp_path: Path) -> None:
    """``cfgplan launch --keys``: the society's router starts first, with its
    own certificate (the keys' router's), listening on TLS, and each robot is
    its client (before: a mesh, or with --topology router a usage error).
    Emil's compass fails at cycle 60: the society switches 44 -> 47 through
    the router, Pippi installs the switch and Emil crosses on her data after
    it; the launch ends with Emil's --duration, exit 0, no pid left, and no
    robot warns of a society without keys."""
    keys = _keys(tmp_path / "keys")
    launched = _launch(
        "--impl", str(EXAMPLE_IMPL), "--rate", "20", "--duration", "12", "--keys", str(keys),
        "--inject", "fail compass(Emil) at cycle 60", "--trace", str(tmp_path / "run.jsonl"),
    )  # fmt: skip
    lines, reader, until = _follow(launched)
    try:
        until("Emil sees Pippi", lambda: "Emil: robot Pippi seen" in "".join(lines))
        launched.wait(LIMIT)
    finally:
        said = _ended(launched, lines, reader)
    pids = _pids(said)
    assert list(pids) == ["router", "Emil", "Pippi"], said
    secured = (
        rf"^router +\| router \w+ listening on tls/127\.0\.0\.1:\d+ \(keys of {SOCIETY}/router/"
    )
    assert re.search(secured, said, re.M), said
    emil = read_trace(tmp_path / "run-emil.jsonl")
    switch = next(r for r in emil if r["event"] == "switch")
    assert (switch["from_cost"], switch["to_cost"]) == (44, 47)
    pippi = read_trace(tmp_path / "run-pippi.jsonl")
    assert [r["id"] for r in pippi if r["event"] == "install"][-1] == switch["id"]
    assert cross_door_served(tmp_path / "run-emil.jsonl", float(switch["t"]))()  # type: ignore[arg-type]
    assert "without keys" not in said
    assert all(_gone(pid) for pid in pids.values())


def _unchecked(keys: Path, name: str, port: int) -> Any:
    """A client of the router with ``name``'s valid certificate and no access
    control of its own: what it sends is held back by the router alone."""
    hermetic = str(hermetic_config(keys.parent))
    options = ZenohOptions(SOCIETY, config_file=hermetic, keys=str(keys), router=(endpoint(port),))
    config = zenoh_config(options, name)
    config.insert_json5("access_control", '{"enabled": false}')
    return config


@pytest.mark.slow
def test_the_secured_router_refuses_strangers_and_holds_members_to_their_rights(
    tmp_path: Path,
) -> None:
    """``cfgplan router --keys``: a client without a certificate, one with a
    certificate of another authority (same society, same names), and one over
    plain TCP cannot open a session with it. A member with a valid certificate
    and no access control of its own (an attacker controls its own session)
    puts a value on Pippi's channel in Pippi's name, a switch to Pippi (Eve is
    no coordinator) and Pippi's liveliness token: the router lets none of them
    through, though Pippi's session, whose own access control takes all of them
    from the router, listens on each; the value the same member sends in its
    own name, after them on the same link, arrives (before: cfgplan router had
    no --keys, and --router could not go with --keys)."""
    keys = _keys(tmp_path / "keys")
    rival = _keys(tmp_path / "rival-keys")  # another authority, the same names
    port = free_port()
    tls = f"tls/127.0.0.1:{port}"
    with processes() as running:
        log = tmp_path / "router.log"
        serving = ["-m", "cfgplan", "router", "--listen", endpoint(port), "--keys", str(keys)]
        router = running.start(serving, log)

        def listens() -> bool | None:
            return (log.exists() and "listening on tls/" in log.read_text()) or None

        wait_for("the router listens", listens, LIMIT)
        of_rival = {
            "root_ca_certificate": str(rival / "ca.pem"),
            "connect_private_key": str(rival / "eve.key"),
            "connect_certificate": str(rival / "eve.pem"),
            "verify_name_on_connect": False,
        }
        bare = {"root_ca_certificate": str(keys / "ca.pem"), "verify_name_on_connect": False}
        for what, config in (
            ("plain TCP", stranger(endpoint(port))),
            ("TLS without a certificate", stranger(tls, bare)),
            ("a certificate of another authority", stranger(tls, of_rival)),
        ):
            config.insert_json5("mode", '"client"')
            with pytest.raises(zenoh.ZError), session(config):
                pass
            assert router.poll() is None, what
        pippis = ZenohOptions(
            SOCIETY,
            config_file=str(hermetic_config(tmp_path)),
            keys=str(keys),
            router=(endpoint(port),),
        )
        with (
            session(zenoh_config(pippis, "Pippi")) as pippi,
            session(_unchecked(keys, "Emil", port)) as emil,
            session(_unchecked(keys, "Eve", port)) as eve,
        ):
            inbox = Inbox()
            for key in (f"{P}/Pippi/ch/**", f"{P}/Pippi/configure"):  # what she may be sent
                pippi.declare_subscriber(key, inbox)
            pippi.liveliness().declare_subscriber(f"{P}/*/alive", inbox, history=True)
            tokens = [  # held: a token dropped is undeclared
                emil.liveliness().declare_token(f"{P}/Emil/alive"),
                eve.liveliness().declare_token(f"{P}/Pippi/alive"),
            ]
            assert inbox.wait(lambda k: k == f"{P}/Emil/alive", LIMIT), inbox.names()

            def forged_then_own() -> bool:
                eve.put(f"{P}/Pippi/configure", json.dumps({"op": "finish"}))
                emil.put(f"{P}/Pippi/ch/Pippi/F1/F2/pos", "[0, 0]")
                emil.put(f"{P}/Pippi/ch/Emil/F1/F2/pos", "[1, 1]")
                return inbox.wait(lambda k: k == f"{P}/Pippi/ch/Emil/F1/F2/pos", 0.5)

            wait_for("Emil's own value", lambda: forged_then_own() or None, LIMIT)
            time.sleep(QUIET)
            got = set(inbox.names())
            assert f"{P}/Pippi/ch/Pippi/F1/F2/pos" not in got, "a value in Pippi's name"
            assert f"{P}/Pippi/configure" not in got, "a switch from Eve, who coordinates nothing"
            assert f"{P}/Pippi/alive" not in got, "Pippi's token, declared by Eve"
            for token in tokens:
                token.undeclare()
        assert router.poll() is None


@pytest.mark.slow
def test_the_society_serves_its_goal_again_after_its_secured_router_froze(
    tmp_path: Path,
) -> None:
    """A launch with keys, lease 1 s. The secured router is frozen (SIGSTOP)
    for 4 s: the robots lose it, and so each other; after SIGCONT the clients
    connect to it again over TLS, and Emil serves his goal on Pippi's data
    again. SIGTERM then stops every process (before: with --keys launch
    made a mesh, with no router to freeze). A router killed and started again
    is tests/cli/test_launch.py's, with keys too."""
    keys = _keys(tmp_path / "keys")
    launched = _launch(
        "--impl", str(EXAMPLE_IMPL), "--rate", "20", "--lease", "1", "--keys", str(keys),
        "--trace", str(tmp_path / "run.jsonl"),
    )  # fmt: skip
    lines, reader, until = _follow(launched)
    emil = tmp_path / "run-emil.jsonl"
    try:
        until("the goal served", cross_door_served(emil, 0.0))
        pids = _pids("".join(lines))
        frozen = time.monotonic()
        os.kill(pids["router"], signal.SIGSTOP)
        try:
            until("Emil sees Pippi lost", lambda: "Emil: robot Pippi lost" in "".join(lines))
            time.sleep(max(0.0, frozen + FREEZE - time.monotonic()))
        finally:
            resumed = time.time()
            os.kill(pids["router"], signal.SIGCONT)
        until("Emil sees Pippi again", lambda: "".join(lines).count("Emil: robot Pippi seen") == 2)
        until("the goal served after the freeze", cross_door_served(emil, resumed))
        launched.send_signal(signal.SIGTERM)
        launched.wait(LIMIT)
    finally:
        said = _ended(launched, lines, reader)
    assert all(_gone(pid) for pid in pids.values()), said
