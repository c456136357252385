"""``--live [HOST:]PORT``: where the live page is served.

HOST defaults to 127.0.0.1, this machine only: the page shows the society's
internals (its configuration, failures, costs) to anyone who can reach it,
with no login, so it is opened to a network only when asked for
(``0.0.0.0:8080``, or the address of one interface). An IPv6 host is written
in brackets, ``[::1]:8080``. Port 0 picks a free port.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["DEFAULT_HOST", "Address", "parse_address"]

DEFAULT_HOST = "127.0.0.1"


@dataclass(frozen=True)
class Address:
    """A host and a port to listen on (port 0: any free one)."""

    host: str
    port: int

    def url(self, port: int | None = None) -> str:
        """The page's URL (``port``: the one actually bound)."""
        host = f"[{self.host}]" if ":" in self.host else self.host
        if self.host in ("0.0.0.0", "::"):
            host = "127.0.0.1" if self.host == "0.0.0.0" else "[::1]"
        return f"http://{host}:{self.port if port is None else port}/"


def parse_address(text: str) -> Address:
    """``8080``, ``0``, ``0.0.0.0:8080``, ``[::1]:8080`` -> :class:`Address`;
    a ``ValueError`` saying what is wrong otherwise."""
    text = text.strip()
    host, port = DEFAULT_HOST, text
    if text.startswith("["):
        end = text.find("]")
        if end < 0 or not text[end + 1 :].startswith(":"):
            raise ValueError(f"expected [HOST]:PORT, not {text!r}")
        host, port = text[1:end], text[end + 2 :]
    elif ":" in text:
        host, _, port = text.rpartition(":")
        if ":" in host:
            raise ValueError(f"write an IPv6 host in brackets, [{host}]:{port}")
    if not host:
        raise ValueError(f"expected [HOST:]PORT, not {text!r}")
    if not port.isdigit() or not 0 <= int(port) <= 65535:
        raise ValueError(f"a port is a whole number from 0 to 65535, not {port!r}")
    return Address(host, int(port))
