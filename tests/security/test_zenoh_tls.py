"""How ``--keys DIR`` becomes a robot's Zenoh configuration, checked against the
installed eclipse-zenoh's configuration schema (no network)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

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
    plan = plan_society("lab", ["Emil", "Pippi"], ["console"], ["Emil"])
    write_society(folder, make_society(plan), force=False)
    return folder


def _get(options: ZenohOptions, robot: str, key: str) -> object:
    return json.loads(zenoh_config(options, robot).get_json(key))  # type: ignore[no-any-return]


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
    rules = {r["id"]: r for r in acl["rules"]}
    names = {s["id"]: s["cert_common_names"] for s in acl["subjects"]}

    def allowed(cn: str, flow: str, message: str) -> set[str]:
        (policy,) = [p for p in acl["policies"] if [cn] in (names[s] for s in p["subjects"])]
        return {
            k
            for r in policy["rules"]
            if flow in rules[r]["flows"] and message in rules[r]["messages"]
            for k in rules[r]["key_exprs"]
        }

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
    assert access_control(society_of(keys))["rules"] == acl["rules"]


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
