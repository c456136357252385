"""How ``--record FILE.mcap`` writes: how often, how much.

Light: no ``mcap`` here, so the command line can say the defaults without
loading the recorder. The policy, documented in "Record a run for Foxglove":

* **as it happens** — messages gather in an MCAP chunk, which is finished
  (compressed, written, its message index after it) and handed to the
  operating system every :attr:`Policy.flush_every` seconds, at once after a
  switch, a failure, a recovery or another event of the society (5.5), and
  whenever it reaches :attr:`Policy.chunk_size`. A run killed even by SIGKILL
  leaves every chunk finished before: the file lacks only its summary and
  footer, and a streaming reader (``mcap recover``, or
  :func:`cfgplan.record.live.salvage`) reads it;
* **bounded** like ``--trace`` (:mod:`cfgplan.runtime.tracefile`): a value
  longer than :attr:`Policy.elide` characters of JSON is recorded by its size
  and digest, and when the file would pass :attr:`Policy.max_bytes` it is
  finished (summary and footer), renamed FILE.1 (replacing an earlier one)
  and a new FILE begins: at most about twice the cap on disk, the newest
  events in FILE.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from cfgplan.runtime.tracefile import ELIDE, MAX_BYTES

__all__ = ["FOXGLOVE_HINT", "RECORD_HINT", "Policy"]

RECORD_HINT = "pip install 'cfgplan[record]'"
"""How to get what ``--record`` needs (the ``mcap`` package)."""

FOXGLOVE_HINT = "pip install 'cfgplan[foxglove]'"
"""How to get what ``--foxglove`` needs (the ``foxglove-sdk`` package)."""


@dataclass(frozen=True)
class Policy:
    """How a recording is written (module docstring)."""

    max_bytes: int = MAX_BYTES
    """The cap of FILE in bytes (64 MiB, as ``--trace``; 0: no cap), then FILE.1."""
    flush_every: float = 1.0
    """Seconds at most between a message and its chunk being on disk (0: each message)."""
    chunk_size: int = 1 << 20
    """Bytes of messages (uncompressed) at which a chunk is finished anyway."""
    compression: Literal["zstd", "lz4", "none"] = "zstd"
    elide: int = ELIDE
    """Characters of JSON beyond which a value is recorded by its size and digest (0: whole)."""
