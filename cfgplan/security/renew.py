"""Rotating one member's key with the society's own authority (``cfgplan keys renew``).

A robot's key that leaked, or a certificate about to expire, is replaced
without making the society's keys again: in the folder where they were made
(it holds the CA's key, ``ca.key``), :func:`renew` makes the member a new key
and a certificate signed by the same CA, one *generation* on, whose common
name says so (``lab/Pippi@2``, :func:`cfgplan.security.keys.common_name`),
and writes ``society.json`` naming that generation. What each host then needs:

* the member's host: its new ``<stem>.pem`` and ``<stem>.key`` (and the new
  ``society.json``);
* every other host: the new ``society.json`` only (public, no secret); the
  CA and the other members' keys do not change.

What it revokes: Zenoh's access control (:mod:`cfgplan.security.zenoh_tls`)
admits only the common names ``society.json`` lists, deny by default. A peer
with the old certificate still completes the TLS handshake (the CA signed
it) but may publish, subscribe to and declare nothing with any member that
has the new ``society.json``. What it does not revoke: a member that still
has the old ``society.json`` goes on admitting the old certificate (and
refuses the new one) until it is given the new file and restarted — access
control is read when a session opens. There is no certificate revocation
list: a certificate is refused by the name it carries, so a society's
members must all have the new ``society.json`` for the rotation to hold.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import Any

from cfgplan.run_errors import RunError
from cfgplan.security.keys import (
    CA_STEM,
    MANIFEST,
    MAX_COMMON_NAME,
    Member,
    SocietyKeys,
    _crypto,
    common_name,
    member_files,
    read_society,
)

__all__ = ["renew"]


def _authority(folder: Path) -> tuple[Any, Any]:
    """The CA's private key and name, from ``ca.key`` and ``ca.pem`` of ``folder``."""
    x509 = _crypto()
    from cryptography.hazmat.primitives import serialization

    pem, key = folder / f"{CA_STEM}.pem", folder / f"{CA_STEM}.key"
    if not key.is_file():
        raise RunError(
            f"{key} not found: renewing a key needs the society's authority",
            hint="run it where the society's keys were made (cfgplan keys new)",
        )
    try:
        ca_cert = x509.load_pem_x509_certificate(pem.read_bytes())
        ca_key = serialization.load_pem_private_key(key.read_bytes(), password=None)
    except (OSError, ValueError, TypeError) as exc:
        raise RunError(f"cannot read the society's authority in {folder}: {exc}") from None
    spki = (serialization.Encoding.DER, serialization.PublicFormat.SubjectPublicKeyInfo)
    if ca_cert.public_key().public_bytes(*spki) != ca_key.public_key().public_bytes(*spki):
        raise RunError(f"{key} is not the key of {pem}")
    return ca_key, ca_cert.subject


def renew(folder: Path, name: str, days: int) -> tuple[Member, Member, dict[str, bytes]]:
    """Member ``name`` (a robot, else an operator tool, else a router) of the keys in
    ``folder`` as it was and as it becomes, and the files to write: its new
    key and certificate, and ``society.json``."""
    keys = read_society(folder)
    old = keys.named(name)
    if old is None:
        members = ", ".join(m.name for m in keys.members)
        raise RunError(
            f"{folder} has no member {name} (society {keys.society}: {members})",
            hint="a new member needs the society's keys made again: cfgplan keys new",
        )
    generation = old.generation + 1
    cn = common_name(keys.society, old.name, old.kind, generation)
    if len(cn) > MAX_COMMON_NAME:
        most = MAX_COMMON_NAME
        raise RunError(f"{cn!r}: a certificate's common name has at most {most} characters")
    new = replace(old, common_name=cn, generation=generation)
    ca_key, ca_name = _authority(folder)
    files = member_files(keys.society, new, ca_key, ca_name, days)
    renewed = tuple(new if m is old else m for m in keys.members)
    files[MANIFEST] = SocietyKeys(keys.society, renewed).to_json().encode("utf-8")
    return old, new, files
