"""``cfgplan keys renew NAME -o DIR``: one member's key rotated with the society's own
authority; where the new society.json is, the old certificate can do nothing.

The sessions are configured as robot programs configure theirs (hermetic:
loopback, free ports, scouting off, bounded waits)."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import pytest
from cryptography import x509
from cryptography.x509.oid import NameOID

from cfgplan.runtime.zenoh_transport import ZenohOptions, zenoh_config
from cfgplan.security.keys import make_society, plan_society, read_society, write_society
from tests.backends.support import ROOT
from tests.runtime.netutil import free_port, hermetic_config

SOCIETY = "renew-test"
P = f"cfgplan/{SOCIETY}"
LIMIT = 30.0


def _cfgplan(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "cfgplan", *args],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=120,
    )


def _keys(folder: Path) -> Path:
    plan = plan_society(SOCIETY, ["Emil", "Pippi"], ["console"], ["Emil"])
    write_society(folder, make_society(plan), force=False)
    return folder


def _cn(path: Path) -> str:
    cert = x509.load_pem_x509_certificate(path.read_bytes())
    return str(cert.subject.get_attributes_for_oid(NameOID.COMMON_NAME)[0].value)


def test_renew_replaces_one_members_files_and_names_its_generation(tmp_path: Path) -> None:
    """Pippi's key and certificate are new, of generation 2 (common name
    renew-test/Pippi@2), signed by the same CA; society.json names the new
    common name; the CA and Emil's files are untouched; every file stays 0600;
    nothing secret is printed. Twice: generation 3."""
    keys = _keys(tmp_path / "keys")
    before = {p.name: p.read_bytes() for p in keys.iterdir()}
    out = _cfgplan("keys", "renew", "Pippi", "-o", str(keys))
    assert out.returncode == 0, out.stderr
    assert "PRIVATE KEY" not in out.stdout + out.stderr
    assert "renew-test/Pippi@2" in out.stdout
    after = {p.name: p.read_bytes() for p in keys.iterdir()}
    changed = {name for name in before if before[name] != after[name]}
    assert changed == {"pippi.pem", "pippi.key", "society.json"}
    assert _cn(keys / "pippi.pem") == "renew-test/Pippi@2"
    ca = x509.load_pem_x509_certificate((keys / "ca.pem").read_bytes())
    x509.load_pem_x509_certificate((keys / "pippi.pem").read_bytes()).verify_directly_issued_by(ca)
    pippi = read_society(keys).member("Pippi")
    assert pippi is not None and (pippi.generation, pippi.common_name) == (2, "renew-test/Pippi@2")
    assert all(p.stat().st_mode & 0o777 == 0o600 for p in keys.iterdir())
    assert _cfgplan("keys", "renew", "Pippi", "-o", str(keys)).returncode == 0
    assert _cn(keys / "pippi.pem") == "renew-test/Pippi@3"


def test_the_routers_key_is_renewed_like_a_robots(tmp_path: Path) -> None:
    """The society's router (its key made by cfgplan keys new): renewed, its
    common name names its generation, and a robot's session admits the new
    router and no longer the old one (before: renew knew robots and operator
    tools only)."""
    from cfgplan.security.renew import renew
    from cfgplan.security.zenoh_tls import access_control

    keys = tmp_path / "keys"
    plan = plan_society(SOCIETY, ["Emil", "Pippi"], (), ["Emil"], ["router"])
    write_society(keys, make_society(plan), force=False)
    old, new, files = renew(keys, "router", 30)
    assert (old.common_name, new.common_name) == (
        "renew-test/router/router",
        f"{old.common_name}@2",
    )
    write_society(keys, files, force=True)
    assert _cn(keys / "router.pem") == "renew-test/router/router@2"
    society = read_society(keys)
    names = [s["cert_common_names"] for s in access_control(society, society.robots[0])["subjects"]]
    assert ["renew-test/router/router@2"] in names and [old.common_name] not in names


@pytest.mark.slow
def test_renew_refuses_clearly(tmp_path: Path) -> None:
    """An unknown member, a folder without ca.key (a robot's host), or no keys
    at all: exit 1, a message and no traceback; no name: usage, exit 2."""
    keys = _keys(tmp_path / "keys")
    unknown = _cfgplan("keys", "renew", "Bob", "-o", str(keys))
    assert unknown.returncode == 1 and "no member Bob" in unknown.stderr
    host = tmp_path / "host"
    host.mkdir(mode=0o700)
    for name in ("society.json", "ca.pem", "pippi.pem", "pippi.key"):
        shutil.copy2(keys / name, host / name)
    no_ca = _cfgplan("keys", "renew", "Pippi", "-o", str(host))
    assert no_ca.returncode == 1 and "needs the society's authority" in no_ca.stderr
    none = _cfgplan("keys", "renew", "Pippi", "-o", str(tmp_path / "nothing"))
    assert none.returncode == 1 and "society.json not found" in none.stderr
    assert not (tmp_path / "nothing").exists()
    assert _cfgplan("keys", "renew", "-o", str(keys)).returncode == 2
    for out in (unknown, no_ca, none):
        assert "Traceback" not in out.stderr


zenoh = pytest.importorskip("zenoh")


@contextmanager
def _session(keys: Path, name: str, listen: str = "", connect: str = "") -> Iterator[Any]:
    options = ZenohOptions(
        SOCIETY,
        (listen,) if listen else (),
        (connect,) if connect else (),
        str(hermetic_config(keys.parent)),
        keys=str(keys),
    )
    opened = zenoh.open(zenoh_config(options, name))
    try:
        yield opened
    finally:
        opened.close()


class Inbox:
    def __init__(self) -> None:
        self.got: list[bytes] = []
        self.event = threading.Event()

    def __call__(self, sample: Any) -> None:
        self.got.append(sample.payload.to_bytes())
        self.event.set()

    def wait_for(self, payload: bytes, limit: float) -> bool:
        deadline = time.monotonic() + limit
        while time.monotonic() < deadline:
            if payload in self.got:
                return True
            self.event.wait(0.05)
            self.event.clear()
        return False


@pytest.mark.slow
def test_the_old_certificate_can_no_longer_publish_the_new_one_can(tmp_path: Path) -> None:
    """Emil runs with the renewed society.json. Pippi's old certificate still
    completes the TLS handshake (the session connects: the CA signed it) but
    what it puts on Pippi's own channel into Emil never arrives; the new
    certificate's put on the same key does. A member that still has the old
    society.json (Emil's old folder) admits the old certificate: what the
    rotation does not revoke, said in the docs."""
    keys = _keys(tmp_path / "keys")
    old = tmp_path / "old-keys"
    shutil.copytree(keys, old)
    assert _cfgplan("keys", "renew", "Pippi", "-o", str(keys)).returncode == 0
    key = f"{P}/Emil/ch/Pippi/F7/F3/pos/Emil/Door1"
    for emils, admitted in ((keys, b"new"), (old, b"old")):
        where = f"tls/127.0.0.1:{free_port()}"
        inbox = Inbox()
        with _session(emils, "Emil", listen=where) as emil:
            emil.declare_subscriber(f"{P}/Emil/ch/**", inbox)
            with (
                _session(old, "Pippi", connect=where) as stale,
                _session(keys, "Pippi", connect=where) as fresh,
            ):
                deadline = time.monotonic() + LIMIT
                while time.monotonic() < deadline and len(list(emil.info.peers_zid())) < 2:
                    time.sleep(0.05)
                assert len(list(emil.info.peers_zid())) == 2, "a certificate of the CA was refused"
                time.sleep(1.0)  # the subscription reaches both
                stale.put(key, b"old")
                fresh.put(key, b"new")
                assert inbox.wait_for(admitted, LIMIT), f"{admitted!r} never arrived"
                time.sleep(1.0)
        if admitted == b"new":
            assert inbox.got == [b"new"], "the old certificate still publishes"
        else:  # Emil's old society.json: the old certificate, not the new one
            assert inbox.got == [b"old"]
    assert json.loads((keys / "society.json").read_text())["society"] == SOCIETY
