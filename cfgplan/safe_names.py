"""Safe file names for names read from a domain or a state.

A robot's name comes from the user's input and may be anything the reader
accepts as a symbol: ``../../escaped``, ``/etc/passwd``, ``a\\b``, a NUL, ``CON``,
two names that differ only in case, 10,000 characters. A writer that puts a
file per name (``cfgplan emit``: one per robot; later traces and simulation
outputs) must never let such a name choose where the file goes. Every writer
takes its file names from :func:`file_stems`:

* a name made of ASCII letters, digits, ``_`` and ``-`` (not first), at most
  :data:`MAX_STEM` characters and not a Windows device name (``CON``, ``NUL``,
  ``COM1`` ...), keeps its name in lower case: ``Emil`` -> ``emil``, as the
  thesis's robots always did;
* any other name keeps its safe characters and gets ``-`` and 8 hex digits of
  the SHA-256 of the name: ``../../escaped`` -> ``escaped-3b3f4a64``;
* names whose stems collide (``Emil`` and ``EMIL``, or a name and a stem the
  writer reserves, such as ``run_all``) all get the digest, lengthened until
  the stems differ.

So a stem is one path component of ``[a-z0-9_-]``, never empty, never ``.`` or
``..``, never longer than 60 + 65 characters, the same on every run and on every
operating system (case-insensitive file systems included). Writers show the
mapping (``cfgplan emit`` in ``configuration.txt``) since a stem with a digest
does not tell its name back.
"""

from __future__ import annotations

import hashlib
import re
from collections.abc import Iterable

__all__ = ["MAX_STEM", "file_stems", "is_safe_stem", "safe_stem"]

MAX_STEM = 60
"""Longest stem kept without a digest (and the longest prefix kept with one)."""

_SAFE = re.compile(r"[a-z0-9_][a-z0-9_-]*")
_UNSAFE_RUN = re.compile(r"[^a-z0-9_-]+")
_WINDOWS_DEVICES = frozenset(
    ["con", "prn", "aux", "nul"] + [f"com{i}" for i in range(10)] + [f"lpt{i}" for i in range(10)]
)


def _digest(name: str, length: int) -> str:
    return hashlib.sha256(name.encode("utf-8", "surrogatepass")).hexdigest()[:length]


def _base(name: str) -> str:
    """The safe characters of ``name``, lower case, runs of others as one ``_``,
    no ``_`` or ``-`` at either end, at most :data:`MAX_STEM` characters."""
    return _UNSAFE_RUN.sub("_", name.lower()).strip("_-")[:MAX_STEM].strip("_-")


def is_safe_stem(stem: str) -> bool:
    """True when ``stem`` can be used as it is (no digest needed)."""
    return (
        len(stem) <= MAX_STEM and _SAFE.fullmatch(stem) is not None and stem not in _WINDOWS_DEVICES
    )


def safe_stem(name: str, digest: int = 8) -> str:
    """The stem of ``name`` on its own (see the module docstring); ``digest``
    hex digits are added when the name is not already safe."""
    lowered = name.lower()
    if is_safe_stem(lowered):
        return lowered
    return f"{_base(name) or 'name'}-{_digest(name, digest)}"


def file_stems(names: Iterable[str], reserved: Iterable[str] = ()) -> dict[str, str]:
    """A distinct safe stem for each of ``names`` (in their order), none equal to
    one of ``reserved`` (compared in lower case)."""
    unique = list(dict.fromkeys(names))
    taken = {r.lower() for r in reserved}
    stems = {n: safe_stem(n) for n in unique}
    for digest in (16, 32, 64, 0):
        count: dict[str, int] = {}
        for stem in stems.values():
            count[stem] = count.get(stem, 0) + 1
        clashing = [n for n, s in stems.items() if count[s] > 1 or s in taken]
        if not clashing:
            return stems
        if not digest:  # pragma: no cover - distinct names have distinct SHA-256
            break
        for n in clashing:
            stems[n] = f"{_base(n) or 'name'}-{_digest(n, digest)}"
    raise ValueError(f"no distinct file names for {clashing!r}")
