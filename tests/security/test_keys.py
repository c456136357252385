"""``cfgplan keys new``: a society's CA and its members' keys, owner-only, never
overwritten without --force, nothing secret printed."""

from __future__ import annotations

import json
import os
import stat
import subprocess
import sys
from pathlib import Path

import pytest
from cryptography import x509
from cryptography.x509.oid import NameOID

from cfgplan.runtime import RunError
from cfgplan.security.keys import common_name, make_society, plan_society, write_society
from tests.backends.support import DOMAINS, ROOT

STEP1 = ["--domain", str(DOMAINS / "cross-door/domain.lisp")]
STEP1 += ["--state", str(DOMAINS / "cross-door/state-6.2.2-sequence.lisp")]


def _cfgplan(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "cfgplan", *args],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=120,
    )


def _cn(path: Path) -> str:
    cert = x509.load_pem_x509_certificate(path.read_bytes())
    return str(cert.subject.get_attributes_for_oid(NameOID.COMMON_NAME)[0].value)


def test_keys_for_every_robot_of_a_state_owner_only_and_signed_by_the_ca(
    tmp_path: Path,
) -> None:
    """One CA, one key and certificate per robot and operator and one for the
    society's router, each file 0600 in
    a folder 0700; each certificate names its society and member and is signed by
    the CA; the coordinators are the robots the goals name first (a sequence:
    Pippi, then Emil); the output names files and never shows a key."""
    folder = tmp_path / "keys"
    out = _cfgplan("keys", "new", "lab", "-o", str(folder), *STEP1, "--operator", "console")
    assert out.returncode == 0, out.stderr
    names = {p.name for p in folder.iterdir()}
    assert names == {
        "ca.pem",
        "ca.key",
        "pippi.pem",
        "pippi.key",
        "emil.pem",
        "emil.key",
        "console.pem",
        "console.key",
        "router.pem",
        "router.key",
        "society.json",
    }
    assert stat.S_IMODE(folder.stat().st_mode) == 0o700
    for path in folder.iterdir():
        assert stat.S_IMODE(path.stat().st_mode) == 0o600, path
    ca = x509.load_pem_x509_certificate((folder / "ca.pem").read_bytes())
    for stem, cn in (
        ("emil", "lab/Emil"),
        ("pippi", "lab/Pippi"),
        ("console", "lab/operator/console"),
        ("router", "lab/router/router"),
    ):
        assert _cn(folder / f"{stem}.pem") == cn
        x509.load_pem_x509_certificate(
            (folder / f"{stem}.pem").read_bytes()
        ).verify_directly_issued_by(ca)
    society = json.loads((folder / "society.json").read_text())
    leading = {m["name"] for m in society["members"] if m["coordinator"]}
    assert society["society"] == "lab" and leading == {"Pippi", "Emil"}
    assert [m["name"] for m in society["members"] if m["kind"] == "router"] == ["router"]
    assert "router.pem    the router's certificate, lab/router/router" in out.stdout
    printed = out.stdout + out.stderr
    assert "emil.key" in printed and "PRIVATE KEY" not in printed
    for key in folder.glob("*.key"):
        body = "".join(key.read_text().splitlines()[1:-1])
        assert body[:40] not in printed


@pytest.mark.slow
def test_refuses_to_overwrite_without_force_and_a_folder_others_can_enter(
    tmp_path: Path,
) -> None:
    folder = tmp_path / "keys"
    args = ["keys", "new", "lab", "-o", str(folder), "--robot", "Emil", "--coordinator", "Emil"]
    assert _cfgplan(*args).returncode == 0
    before = (folder / "ca.key").read_bytes()
    again = _cfgplan(*args)
    assert again.returncode == 1 and "pass --force" in again.stderr
    assert "Traceback" not in again.stderr
    assert (folder / "ca.key").read_bytes() == before
    assert _cfgplan(*args, "--force").returncode == 0
    assert (folder / "ca.key").read_bytes() != before
    assert stat.S_IMODE((folder / "ca.key").stat().st_mode) == 0o600
    shared = tmp_path / "shared"
    shared.mkdir()
    os.chmod(shared, 0o755)
    refused = _cfgplan(
        "keys", "new", "lab", "-o", str(shared), "--robot", "A", "--coordinator", "A"
    )
    assert refused.returncode == 1 and "mode 0755" in refused.stderr
    assert not list(shared.iterdir())


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--robot", "Emil"], "--coordinator"),
        ([], "no robot"),
        (["--state", "s.lisp"], "--domain DOMAIN and --state STATE together"),
        (["--robot", "Emil", "--coordinator", "Pippi"], "not one of the robots"),
    ],
)
def test_bad_command_lines_say_what_to_give(tmp_path: Path, args: list[str], message: str) -> None:
    out = _cfgplan("keys", "new", "lab", "-o", str(tmp_path / "k"), *args)
    assert out.returncode in (1, 2) and message in out.stderr, out.stderr
    assert "Traceback" not in out.stderr


def test_names_that_cannot_be_files_or_common_names(tmp_path: Path) -> None:
    """A robot name is never a path (its file stem is made safe, the common name
    escaped); a common name past X.509's 64 characters is refused."""
    plan = plan_society("lab", ["../../etc/x", "Emil"], coordinators=["Emil"])
    (odd, emil) = plan.members
    assert "/" not in odd.stem and odd.stem != ".." and emil.stem == "emil"
    assert odd.common_name == common_name("lab", "../../etc/x", "robot") == "lab/..%2F..%2Fetc%2Fx"
    written = write_society(tmp_path / "k", make_society(plan), force=False)
    assert all(p.parent == tmp_path / "k" for p in written)
    with pytest.raises(RunError, match="at most 64"):
        plan_society("x" * 70, ["Emil"], coordinators=["Emil"])
    with pytest.raises(RunError, match="named twice"):
        plan_society("lab", ["Emil"], ["Emil"], ["Emil"])
    with pytest.raises(RunError, match="named twice: router") as clash:
        plan_society("lab", ["router"], (), ["router"], ["router"])
    assert clash.value.hint == "name the router otherwise: --router NAME"
    hub = plan_society("lab", ["router"], (), ["router"], ["hub"])
    assert [(m.kind, m.common_name) for m in hub.members] == [
        ("robot", "lab/router"),
        ("router", "lab/router/hub"),
    ]


def test_without_cryptography_it_says_how_to_install_it(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "cryptography", None)  # import fails as if not installed
    with pytest.raises(RunError) as caught:
        make_society(plan_society("lab", ["Emil"], coordinators=["Emil"]))
    assert "cryptography" in caught.value.message
    assert caught.value.hint is not None and "cfgplan[keys]" in caught.value.hint
