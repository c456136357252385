"""Chunks of a Zenoh key: the names in a key (society, robot, functionality,
data) percent-encoded so that none can be read as a separator or a wildcard.

Below the runtime's key layout (:mod:`cfgplan.runtime.keys`) and the security
package's access rules (:mod:`cfgplan.security.zenoh_tls`), which both build
keys of these chunks: neither imports the other for them.
"""

from __future__ import annotations

import re

__all__ = ["PREFIX", "chunk", "unchunk"]

PREFIX = "cfgplan"
"""The first chunk of every key cfgplan uses."""

_SAFE = re.compile(r"[A-Za-z0-9_.\-+=,:~]")
_ESCAPED = re.compile(r"(?:%[0-9A-F]{2})+")


def chunk(text: str) -> str:
    """One key chunk for ``text``: percent-encoded, never empty."""
    if not text:
        return "%"  # not a valid escape, so it cannot be confused with a name
    return "".join(
        c if _SAFE.fullmatch(c) else "".join(f"%{b:02X}" for b in c.encode()) for c in text
    )


def unchunk(part: str) -> str:
    """The text a chunk stands for (the inverse of :func:`chunk`);
    ``UnicodeDecodeError`` when its escapes are not UTF-8 (``%FF``)."""
    if part == "%":
        return ""
    return _ESCAPED.sub(lambda m: bytes.fromhex(m.group(0).replace("%", "")).decode(), part)
