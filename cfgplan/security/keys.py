"""A society's keys: its certificate authority and one certificate per member.

``cfgplan keys new SOCIETY -o DIR`` (:mod:`cfgplan.cli.keys`) writes, into a
folder only its owner may enter (mode 0700), files only the owner may read
(0600):

* ``ca.pem``, ``ca.key``: the society's certificate authority (CA). Its key
  signs the members' certificates and is needed again only to add or renew
  one: keep it off the robots.
* per member, ``<stem>.pem`` and ``<stem>.key`` (the stem of its name as
  :func:`cfgplan.safe_names.file_stems` makes it, ``Emil`` -> ``emil``): a
  certificate the CA signed, whose common name names the society and the
  member (:func:`common_name`), and its private key. A member is a robot or a
  device of the state (a robot program), an operator tool, or the society's
  Zenoh router (``cfgplan router --keys``), which the robots are clients of
  and which holds each of them to what it may say.
* ``society.json``: the society's name and, per member, its kind, common
  name, file stem, key generation and whether it may coordinate (send the
  switches of 5.5); no secret. :mod:`cfgplan.security.zenoh_tls` builds
  Zenoh's access control from it.

``cfgplan keys renew NAME -o DIR`` (:mod:`cfgplan.security.renew`) gives one member a
new key and certificate, signed by the same CA, of the next *generation*:
its common name ends in ``@2``, ``@3``, ... (``@`` never occurs in a key
chunk, so no member's name reads as another's generation), and
``society.json`` names only the new one. Zenoh's access control admits only
the common names ``society.json`` lists, so wherever the new ``society.json``
is, the old certificate still passes the TLS handshake (the CA signed it)
but may do nothing at all: deny by default.

A robot's host needs ``society.json``, ``ca.pem`` and its own two files; so
does the router's host.

Keys are ECDSA on P-256, certificates X.509 v3 for TLS client and server
alike (a Zenoh peer both listens and connects). Only :func:`make_society`
imports ``cryptography``, the ``keys`` extra of cfgplan.
"""

from __future__ import annotations

import contextlib
import datetime
import json
import os
import stat
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from cfgplan.key_chunks import chunk
from cfgplan.run_errors import RunError
from cfgplan.safe_names import file_stems

__all__ = [
    "CA_STEM",
    "MANIFEST",
    "ROUTER",
    "Member",
    "SocietyKeys",
    "common_name",
    "make_society",
    "member_files",
    "read_society",
    "write_society",
]

MANIFEST = "society.json"
"""The public description of a society's keys, in its folder."""
CA_STEM = "ca"
FORMAT = "cfgplan-keys/1"
MAX_COMMON_NAME = 64
"""X.509's upper bound on a common name (RFC 5280, ub-common-name)."""
INSTALL_HINT = "pip install 'cfgplan[keys]' (or pip install cryptography)"
KINDS = ("robot", "operator", "router")
ROUTER = "router"
"""The name of the router's key that ``cfgplan keys new`` makes unless told another."""


def common_name(society: str, name: str, kind: str, generation: int = 1) -> str:
    """The certificate common name of a member: ``lab/Emil`` for robot Emil of
    society ``lab``, ``lab/operator/console`` for operator tool ``console``,
    ``lab/router/router`` for the society's router ``router``, ``lab/Emil@2``
    for Emil's second key (:mod:`cfgplan.security.renew`). Each part is a key
    chunk (:func:`cfgplan.runtime.keys.chunk`), so a name never contains a raw
    ``/`` nor ``@``, and a robot's name (two parts) never reads as an
    operator's or a router's (three, the second saying which)."""
    again = f"@{generation}" if generation > 1 else ""
    if kind in ("operator", "router"):
        return f"{chunk(society)}/{kind}/{chunk(name)}{again}"
    return f"{chunk(society)}/{chunk(name)}{again}"


@dataclass(frozen=True)
class Member:
    """A robot (or device) program, an operator tool or a router of the society."""

    name: str
    kind: str  # "robot", "operator" or "router"
    stem: str  # its files: <stem>.pem and <stem>.key
    common_name: str
    coordinator: bool = False
    generation: int = 1
    """1 for the key ``cfgplan keys new`` made, one more at each renewal."""


@dataclass(frozen=True)
class SocietyKeys:
    """What ``society.json`` says: the society and its members."""

    society: str
    members: tuple[Member, ...]

    def member(self, name: str, kind: str = "robot") -> Member | None:
        return next((m for m in self.members if m.name == name and m.kind == kind), None)

    def named(self, name: str) -> Member | None:
        """The member ``name``: a robot, else an operator tool, else a router."""
        return next((m for kind in KINDS if (m := self.member(name, kind)) is not None), None)

    @property
    def robots(self) -> tuple[Member, ...]:
        return tuple(m for m in self.members if m.kind == "robot")

    @property
    def routers(self) -> tuple[Member, ...]:
        return tuple(m for m in self.members if m.kind == "router")

    def to_json(self) -> str:
        members = [
            {
                "name": m.name,
                "kind": m.kind,
                "stem": m.stem,
                "common_name": m.common_name,
                "coordinator": m.coordinator,
                "generation": m.generation,
            }
            for m in self.members
        ]
        document = {"format": FORMAT, "society": self.society, "members": members}
        return json.dumps(document, indent=2, ensure_ascii=False) + "\n"


def plan_society(
    society: str,
    robots: Sequence[str],
    operators: Sequence[str] = (),
    coordinators: Iterable[str] = (),
    routers: Sequence[str] = (),
) -> SocietyKeys:
    """The members of a society's keys (nothing is made yet): ``robots``,
    ``operators`` (tools) and ``routers``; :class:`RunError` for names that
    cannot be given certificates."""
    if not society:
        raise RunError("the society name is empty")
    if not robots:
        raise RunError("no robot to make keys for", hint="give --state or --robot NAME")
    names = [*robots, *operators, *routers]
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise RunError(
            f"named twice: {', '.join(twice)} (robots, operator tools and routers need a name "
            "each)",
            hint="name the router otherwise: --router NAME" if set(twice) & set(routers) else None,
        )
    leading = set(coordinators)
    strangers = sorted(leading - set(robots))
    if strangers:
        raise RunError(f"--coordinator {strangers[0]}: not one of the robots ({', '.join(robots)})")
    stems = file_stems(names, reserved=[CA_STEM, "society"])
    members = []
    for name in names:
        kind = "robot" if name in robots else "operator" if name in operators else "router"
        cn = common_name(society, name, kind)
        if len(cn) > MAX_COMMON_NAME:
            raise RunError(
                f"{cn!r}: a certificate's common name has at most {MAX_COMMON_NAME} characters",
                hint="choose a shorter society name",
            )
        members.append(Member(name, kind, stems[name], cn, name in leading))
    return SocietyKeys(society, tuple(members))


def _crypto() -> Any:
    try:
        import cryptography  # noqa: F401
    except ImportError:
        raise RunError(
            "making keys needs the cryptography package, which is not installed",
            hint=INSTALL_HINT,
        ) from None
    from cryptography import x509

    return x509


def _pem_key(key: Any) -> bytes:
    """A private key as unencrypted PKCS #8 PEM (the file is the protection: 0600)."""
    from cryptography.hazmat.primitives import serialization

    return bytes(
        key.private_bytes(
            serialization.Encoding.PEM,
            serialization.PrivateFormat.PKCS8,
            serialization.NoEncryption(),
        )
    )


def _name(society: str, cn: str) -> Any:
    """The X.509 name of a society's CA or member."""
    x509 = _crypto()
    from cryptography.x509.oid import NameOID

    return x509.Name(
        [
            x509.NameAttribute(NameOID.ORGANIZATION_NAME, f"cfgplan society {society}"),
            x509.NameAttribute(NameOID.COMMON_NAME, cn),
        ]
    )


def _validity(days: int) -> tuple[datetime.datetime, datetime.datetime]:
    now = datetime.datetime.now(datetime.UTC)
    start = now - datetime.timedelta(minutes=10)  # robots' clocks differ a little
    return start, now + datetime.timedelta(days=days)


def member_files(
    society: str, member: Member, ca_key: Any, ca_name: Any, days: int
) -> dict[str, bytes]:
    """A new key for ``member`` and its certificate, signed by the CA's key
    ``ca_key`` (whose name is ``ca_name``): ``<stem>.pem`` and ``<stem>.key``."""
    x509 = _crypto()
    from cryptography.hazmat.primitives import hashes, serialization
    from cryptography.hazmat.primitives.asymmetric import ec
    from cryptography.x509.oid import ExtendedKeyUsageOID

    start, end = _validity(days)
    key = ec.generate_private_key(ec.SECP256R1())
    cert = (
        x509.CertificateBuilder()
        .subject_name(_name(society, member.common_name))
        .issuer_name(ca_name)
        .public_key(key.public_key())
        .serial_number(x509.random_serial_number())
        .not_valid_before(start)
        .not_valid_after(end)
        .add_extension(x509.BasicConstraints(ca=False, path_length=None), critical=True)
        .add_extension(
            x509.KeyUsage(True, False, False, False, False, False, False, False, False),
            critical=True,
        )
        .add_extension(
            x509.ExtendedKeyUsage(
                [ExtendedKeyUsageOID.SERVER_AUTH, ExtendedKeyUsageOID.CLIENT_AUTH]
            ),
            critical=False,
        )
        .add_extension(
            x509.SubjectAlternativeName([x509.DNSName(f"{member.stem}.cfgplan.invalid")]),
            critical=False,
        )
        .add_extension(
            x509.AuthorityKeyIdentifier.from_issuer_public_key(ca_key.public_key()), False
        )
        .sign(ca_key, hashes.SHA256())
    )
    return {
        f"{member.stem}.pem": cert.public_bytes(serialization.Encoding.PEM),
        f"{member.stem}.key": _pem_key(key),
    }


def make_society(plan: SocietyKeys, days: int = 730) -> dict[str, bytes]:
    """The files of a society's keys (see the module docstring), by file name."""
    x509 = _crypto()
    from cryptography.hazmat.primitives import hashes, serialization
    from cryptography.hazmat.primitives.asymmetric import ec

    start, end = _validity(days)
    ca_key = ec.generate_private_key(ec.SECP256R1())
    ca_name = _name(plan.society, f"{chunk(plan.society)} CA"[:MAX_COMMON_NAME])
    ca_cert = (
        x509.CertificateBuilder()
        .subject_name(ca_name)
        .issuer_name(ca_name)
        .public_key(ca_key.public_key())
        .serial_number(x509.random_serial_number())
        .not_valid_before(start)
        .not_valid_after(end)
        .add_extension(x509.BasicConstraints(ca=True, path_length=0), critical=True)
        .add_extension(
            x509.KeyUsage(False, False, False, False, False, True, True, False, False),
            critical=True,
        )
        .add_extension(x509.SubjectKeyIdentifier.from_public_key(ca_key.public_key()), False)
        .sign(ca_key, hashes.SHA256())
    )
    files = {
        f"{CA_STEM}.pem": ca_cert.public_bytes(serialization.Encoding.PEM),
        f"{CA_STEM}.key": _pem_key(ca_key),
    }
    for member in plan.members:
        files.update(member_files(plan.society, member, ca_key, ca_name, days))
    files[MANIFEST] = plan.to_json().encode("utf-8")
    return files


def _ready_folder(folder: Path) -> None:
    """Make ``folder`` (mode 0700), or check that only its owner may enter it."""
    try:
        info = folder.lstat()
    except FileNotFoundError:
        try:
            folder.mkdir(mode=0o700, parents=True)
            os.chmod(folder, 0o700)  # mkdir's mode is masked by the umask
        except OSError as exc:
            raise RunError(f"cannot make {folder}: {exc.strerror}") from None
        return
    if stat.S_ISLNK(info.st_mode) or not stat.S_ISDIR(info.st_mode):
        raise RunError(f"{folder} is not a folder (nor a link to one is taken)")
    if info.st_uid != os.getuid() or info.st_mode & 0o077:
        raise RunError(
            f"{folder} can be entered by others (mode {stat.S_IMODE(info.st_mode):04o}); "
            "keys go only into a folder of mode 0700",
            hint=f"give a new folder, or chmod 700 {folder}",
        )


def write_society(folder: Path, files: dict[str, bytes], force: bool) -> list[Path]:
    """Write ``files`` into ``folder``, each of mode 0600, the folder 0700; refuse
    an existing file (or a link) unless ``force``. The paths written, in order."""
    _ready_folder(folder)
    targets = [folder / name for name in files]
    for path in targets:
        if path.is_symlink() or (path.exists() and not path.is_file()):
            raise RunError(f"{path} is not a regular file; cfgplan does not write through it")
    existing = [str(p) for p in targets if p.exists()]
    if existing and not force:
        raise RunError(
            f"{existing[0]} exists{f' (and {len(existing) - 1} more)' if len(existing) > 1 else ''}"
            "; pass --force to replace the society's keys",
            hint="replacing the CA makes every certificate made with it useless",
        )
    for path in targets:
        temporary = path.with_name(f".{path.name}.cfgplan-new")
        with contextlib.suppress(FileNotFoundError):
            temporary.unlink()
        try:
            handle = os.open(temporary, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW, 0o600)
            with os.fdopen(handle, "wb") as out:
                out.write(files[path.name])
            os.chmod(temporary, 0o600)
            os.replace(temporary, path)
        except OSError as exc:
            with contextlib.suppress(OSError):
                temporary.unlink()
            raise RunError(f"cannot write {path}: {exc.strerror}") from None
    return targets


def read_society(folder: Path) -> SocietyKeys:
    """The ``society.json`` of a keys folder; :class:`RunError` when it is missing or wrong."""
    path = folder / MANIFEST
    try:
        document = json.loads(path.read_text("utf-8"))
    except FileNotFoundError:
        raise RunError(
            f"{path} not found: {folder} is not a folder of society keys",
            hint="make one with: cfgplan keys new SOCIETY -o DIR",
        ) from None
    except (OSError, ValueError) as exc:
        raise RunError(f"cannot read {path}: {exc}") from None
    try:
        if document["format"] != FORMAT:
            raise RunError(f"{path}: format {document['format']!r}, not {FORMAT!r}")
        members = tuple(
            Member(
                str(m["name"]),
                str(m["kind"]),
                str(m["stem"]),
                str(m["common_name"]),
                bool(m["coordinator"]),
                _generation(m.get("generation", 1)),
            )
            for m in document["members"]
        )
        society = str(document["society"])
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        raise RunError(f"{path}: not a society's keys ({exc} missing or wrong)") from None
    for m in members:
        if m.kind not in KINDS or "/" in m.stem or m.stem in ("", ".", ".."):
            raise RunError(f"{path}: member {m.name!r} is not well formed")
        if m.common_name != common_name(society, m.name, m.kind, m.generation):
            raise RunError(f"{path}: member {m.name!r} has the common name of another")
    return SocietyKeys(society, members)


def _generation(value: object) -> int:
    if not isinstance(value, int) or isinstance(value, bool) or not 1 <= value <= 1_000_000:
        raise ValueError(f"generation {value!r}")
    return value
