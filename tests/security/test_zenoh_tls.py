"""How ``--keys DIR`` becomes a robot's Zenoh configuration, checked against the
installed eclipse-zenoh's configuration schema (no network)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from cfgplan.runtime import RunError
from cfgplan.runtime.main import parser_of, zenoh_options
from cfgplan.runtime.zenoh_transport import DEFAULT_SOCIETY, ZenohOptions, zenoh_config
from cfgplan.security.keys import make_society, plan_society, write_society
from cfgplan.security.zenoh_tls import access_control, secure_endpoint, society_for, society_of
from tests.backends.support import DOMAINS, EXAMPLE_IMPL, ROOT


@pytest.fixture(scope="module")
def keys(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("society") / "keys"
    plan = plan_society("lab", ["Emil", "Pippi"], ["console"], ["Emil"], ["router"])
    write_society(folder, make_society(plan), force=False)
    return folder


def _get(options: ZenohOptions, robot: str, key: str) -> object:
    return json.loads(zenoh_config(options, robot).get_json(key))  # type: ignore[no-any-return]


def _allowed(acl: Any, cn: str, flow: str, message: str) -> set[str]:
    """The key expressions ``acl`` lets the peer named ``cn`` use ``message`` on in ``flow``."""
    rules = {r["id"]: r for r in acl["rules"]}
    names = {s["id"]: s["cert_common_names"] for s in acl["subjects"]}
    (policy,) = [p for p in acl["policies"] if [cn] in (names[s] for s in p["subjects"])]
    return {
        k
        for r in policy["rules"]
        if flow in rules[r]["flows"] and message in rules[r]["messages"]
        for k in rules[r]["key_exprs"]
    }


def test_the_schema_refuses_what_it_does_not_know() -> None:
    """The checks below mean something: Zenoh's configuration refuses an unknown key."""
    import zenoh

    with pytest.raises(zenoh.ZError):
        zenoh.Config().insert_json5("transport/link/tls/no_such_setting", "true")


def test_tls_with_mutual_authentication_from_the_keys(keys: Path) -> None:
    options = ZenohOptions(society="lab", listen=("tcp/127.0.0.1:7447",), keys=str(keys))
    tls = _get(options, "Emil", "transport/link/tls")
    assert isinstance(tls, dict)
    assert tls["root_ca_certificate"] == str((keys / "ca.pem").resolve())
    assert tls["listen_certificate"] == tls["connect_certificate"] == str(keys / "emil.pem")
    assert tls["listen_private_key"] == tls["connect_private_key"] == str(keys / "emil.key")
    assert tls["enable_mtls"] is True and tls["verify_name_on_connect"] is False
    assert tls["close_link_on_expiration"] is True
    assert _get(options, "Emil", "listen/endpoints") == ["tls/127.0.0.1:7447"]


def test_every_endpoint_becomes_tls_zenohs_default_listener_too(keys: Path, tmp_path: Path) -> None:
    """tcp/ becomes tls/ (options, a --zenoh-config file, Zenoh's own default
    listener on every interface); a protocol that carries no certificate is refused."""
    bare = ZenohOptions(society="lab", keys=str(keys))
    listen = _get(bare, "Pippi", "listen/endpoints")
    assert isinstance(listen, dict) and listen["peer"] == ["tls/[::]:0"]
    assert all(e.startswith("tls/") for mode in listen.values() for e in mode)
    path = tmp_path / "zenoh.json5"
    path.write_text('{ connect: { endpoints: ["tcp/10.0.0.2:7447", "quic/10.0.0.3:7447"] } }')
    filed = ZenohOptions(society="lab", config_file=str(path), keys=str(keys))
    assert _get(filed, "Pippi", "connect/endpoints") == ["tls/10.0.0.2:7447", "quic/10.0.0.3:7447"]
    assert secure_endpoint("tls/[::1]:7447") == "tls/[::1]:7447"
    with pytest.raises(RunError, match="udp carries no certificate"):
        zenoh_config(
            ZenohOptions(society="lab", connect=("udp/1.2.3.4:7",), keys=str(keys)), "Emil"
        )


def test_access_control_of_least_privilege(keys: Path) -> None:
    """Deny by default; per certificate name: a robot puts on the channels it
    sends on and its own key to the coordinator, only a coordinator on the
    configure keys; a robot
    declares only its own token and subscribes only to its own keys; an
    operator tool reads and puts nothing. Zenoh accepts the whole of it."""
    acl = _get(ZenohOptions(society="lab", keys=str(keys)), "Emil", "access_control")
    assert isinstance(acl, dict)
    assert acl["enabled"] is True and acl["default_permission"] == "deny"

    def allowed(cn: str, flow: str, message: str) -> set[str]:
        return _allowed(acl, cn, flow, message)

    assert allowed("lab/Emil", "ingress", "put") >= {"cfgplan/lab/*/configure"}
    assert allowed("lab/Pippi", "ingress", "put") == {  # only keys naming her as the sender
        "cfgplan/lab/*/ch/Pippi/**",
        "cfgplan/lab/coordinator/Pippi",
    }
    assert allowed("lab/Pippi", "ingress", "liveliness_token") == {
        "cfgplan/lab/Pippi/alive",
        "cfgplan/lab/Pippi/process/*",  # each process of hers (a second one is told apart)
        "cfgplan/lab/Pippi/problem/**",  # the problem she runs (cfgplan.security.identity)
    }
    assert allowed("lab/Pippi", "ingress", "declare_subscriber") == {
        "cfgplan/lab/Pippi/ch/**",
        "cfgplan/lab/Pippi/configure",
    }
    assert allowed("lab/operator/console", "ingress", "put") == set()
    pippis = _get(ZenohOptions(society="lab", keys=str(keys)), "Pippi", "access_control")
    assert isinstance(pippis, dict)
    names = [s["cert_common_names"] for s in acl["subjects"]]
    assert names == [["lab/Emil"], ["lab/Pippi"], ["lab/operator/console"], ["lab/router/router"]]
    # the rules of the members are the same in every member's session; the router's are Emil's
    shared = {r for p in acl["policies"][:3] for r in p["rules"]}
    assert [r for r in pippis["rules"] if r["id"] in shared] == [
        r for r in acl["rules"] if r["id"] in shared
    ]
    assert [r for r in access_control(society_of(keys))["rules"] if r["id"] in shared] == [
        r for r in acl["rules"] if r["id"] in shared
    ]


def test_the_router_holds_each_client_to_its_rules_and_each_holds_the_router_to_them(
    keys: Path,
) -> None:
    """The society's router (``cfgplan router --keys``): listens on TLS only, asks
    every client for a certificate of the society's authority, and enforces on
    each the rules the robots enforce among peers (it is no robot: no rule of its
    own on the robots' side but this one). Each robot, a client of it, holds the
    router to its own rules mirrored: the router may send Pippi only what Pippi
    may be sent, and Pippi sends it only what she may send."""
    from cfgplan.runtime.router import RouterOptions, listening, router_config

    options = RouterOptions(listen=("tcp/127.0.0.1:7447",), keys=str(keys))
    config = router_config(options)
    assert json.loads(config.get_json("listen/endpoints")) == ["tls/127.0.0.1:7447"]
    assert listening(options) == ["tls/127.0.0.1:7447"]
    tls = json.loads(config.get_json("transport/link/tls"))
    assert tls["listen_certificate"] == str(keys / "router.pem") and tls["enable_mtls"] is True
    routers = json.loads(config.get_json("access_control"))
    assert routers["default_permission"] == "deny"
    subjects = [s["cert_common_names"] for s in routers["subjects"]]
    assert subjects == [["lab/Emil"], ["lab/Pippi"], ["lab/operator/console"]]  # not itself
    assert _allowed(routers, "lab/Pippi", "ingress", "put") == {
        "cfgplan/lab/*/ch/Pippi/**",
        "cfgplan/lab/coordinator/Pippi",
    }
    assert _allowed(routers, "lab/Pippi", "egress", "put") == {
        "cfgplan/lab/Pippi/ch/**",
        "cfgplan/lab/Pippi/configure",
    }
    client = ZenohOptions(society="lab", router=("tcp/127.0.0.1:7447",), keys=str(keys))
    assert _get(client, "Pippi", "mode") == "client"
    assert _get(client, "Pippi", "connect/endpoints") == ["tls/127.0.0.1:7447"]
    pippis = _get(client, "Pippi", "access_control")
    for flow, other in (("ingress", "egress"), ("egress", "ingress")):
        for message in ("put", "declare_subscriber", "liveliness_token", "reply"):
            assert _allowed(pippis, "lab/router/router", flow, message) == _allowed(
                routers, "lab/Pippi", other, message
            ), (flow, message)
    assert _allowed(pippis, "lab/router/router", "ingress", "put") == {
        "cfgplan/lab/Pippi/ch/**",
        "cfgplan/lab/Pippi/configure",
    }
    emils = _get(client, "Emil", "access_control")
    assert "cfgplan/lab/coordinator/*" in _allowed(emils, "lab/router/router", "ingress", "put")


def test_a_router_without_its_keys_is_refused(keys: Path, tmp_path: Path) -> None:
    """Keys made without a router's (before routers had their own) cannot start
    the secured router; the message says how to make them."""
    from cfgplan.runtime.router import RouterOptions, router_config

    old = tmp_path / "old"
    write_society(old, make_society(plan_society("lab", ["Emil"], (), ["Emil"])), False)
    with pytest.raises(RunError, match="no certificate for a router") as refused:
        router_config(RouterOptions(keys=str(old)))
    assert refused.value.hint is not None and "cfgplan keys new" in refused.value.hint


def test_keys_that_do_not_fit_are_refused(keys: Path, tmp_path: Path) -> None:
    with pytest.raises(RunError, match="for society lab"):
        zenoh_config(ZenohOptions(society="other", keys=str(keys)), "Emil")
    with pytest.raises(RunError, match="no certificate for Eve"):
        zenoh_config(ZenohOptions(society="lab", keys=str(keys)), "Eve")
    with pytest.raises(RunError, match="not a folder of society keys"):
        zenoh_config(ZenohOptions(society="lab", keys=str(tmp_path)), "Emil")
    assert society_for(str(keys), DEFAULT_SOCIETY, DEFAULT_SOCIETY) == "lab"
    assert society_for(None, DEFAULT_SOCIETY, DEFAULT_SOCIETY) == DEFAULT_SOCIETY
    loose = tmp_path / "loose"
    write_society(loose, make_society(plan_society("lab", ["Emil"], coordinators=["Emil"])), False)
    os.chmod(loose / "emil.key", 0o644)
    with pytest.raises(RunError, match="can be read by others"):
        zenoh_config(ZenohOptions(society="lab", keys=str(loose)), "Emil")


def test_run_with_keys_needs_a_robot_on_the_network(keys: Path) -> None:
    args = [str(DOMAINS / "cross-door/domain.lisp")]
    args += [str(DOMAINS / "cross-door/state-6.2.2-step1.lisp"), "--impl", str(EXAMPLE_IMPL)]
    out = subprocess.run(
        [sys.executable, "-m", "cfgplan", "run", *args, "--keys", str(keys)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert out.returncode == 2 and "--keys" in out.stderr and "--robot" in out.stderr


def test_an_emitted_robot_program_takes_keys_and_their_society(keys: Path) -> None:
    """``python emil.py --keys DIR``: the same option as ``cfgplan run``; the
    society is the keys' unless --society names one."""
    parser = parser_of("a robot", network=True)
    args = parser.parse_args(["--impl", "impl.py", "--keys", str(keys)])
    options = zenoh_options(args)
    assert (options.keys, options.society) == (str(keys), "lab")
    other = zenoh_options(parser.parse_args(["--impl", "i.py", "--society", "x"]))
    assert (other.keys, other.society) == (None, "x")


def test_a_society_without_keys_is_said_to_be_open_and_one_with_keys_is_not(
    keys: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Nothing said that anyone on the network could read and steer
    a society. Opening a robot's session without keys now warns, once, on
    stderr (``cfgplan run`` and emitted programs open it the same way)."""
    from cfgplan.runtime.main import open_transport
    from tests.runtime.netutil import endpoint, free_port, hermetic_config

    config = str(hermetic_config(tmp_path))
    for keyed in (None, str(keys)):
        listen = endpoint(free_port())
        if keyed is not None:
            listen = listen.replace("tcp/", "tls/")
        options = ZenohOptions(society="lab", listen=(listen,), config_file=config, keys=keyed)
        transport = open_transport("Emil", "zenoh", options)
        transport.close()
    err = capsys.readouterr().err
    assert err == (
        "cfgplan: warning: society lab runs without keys: anyone on the network can read "
        "and steer it (cfgplan keys new, then --keys DIR)\n"
    )
