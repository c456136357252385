"""An emission: the files one ``cfgplan emit`` wrote into a folder (5.3).

Beside the robots' files, every emission writes :data:`RECORD`, the list of
the files it wrote with their SHA-256 in the format of ``sha256sum``
(``sha256sum -c cfgplan-emission.sha256`` checks them). The record is how a
later ``emit`` tells cfgplan's files from the user's:

- ``emit`` into a folder holding an earlier emission (or any file it would
  write) refuses without ``--force``;
- ``emit --force`` replaces the earlier emission whole: its files that the
  new one does not write (the robot file of a robot no longer in the
  configuration) are removed, so no file of another configuration remains;
- a file cfgplan did not write — not in the record, or changed since cfgplan
  wrote it — is never overwritten or removed, even with ``--force``: ``emit``
  refuses, names every such file, and writes nothing.

The files are written by :func:`cfgplan.files.write_folder` (all written
whole before any is moved into place); the earlier emission's leftovers are
removed after the new files are in place.
"""

from __future__ import annotations

import hashlib
import os
import re
import stat
from collections.abc import Mapping
from pathlib import Path

from cfgplan.diagnostics import CfgplanError, Diagnostic, error
from cfgplan.files import read_source, write_folder

__all__ = ["RECORD", "record_text", "write_emission"]

RECORD = "cfgplan-emission.sha256"
"""The record of an emission, written last into the folder."""

_LINE = re.compile(r"([0-9a-f]{64})  ([^/\\\0]+)")


def _digest(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def record_text(files: Mapping[str, bytes]) -> str:
    """The record of ``files``: ``<sha256>  <name>`` a line, in the order written."""
    return "".join(f"{_digest(data)}  {name}\n" for name, data in files.items())


def _read_record(folder: Path) -> dict[str, str] | None:
    """The earlier emission's record (name -> SHA-256), ``None`` when there is none."""
    path = folder / RECORD
    if not os.path.lexists(path):
        return None
    text = read_source(path).decode("utf-8", errors="replace")
    found: dict[str, str] = {}
    for number, line in enumerate(text.splitlines(), 1):
        match = _LINE.fullmatch(line)
        if match is None:
            raise error(
                f"{path}:{number}: not a line of cfgplan's record of an emission",
                hint="the folder's record was changed by hand; emit into another folder, "
                "or remove the folder's files yourself",
            )
        found[match[2]] = match[1]
    return found


def _current(path: Path) -> str | None:
    """The SHA-256 of the regular file ``path``, ``None`` when it is anything else."""
    try:
        info = path.lstat()
    except OSError:
        return None
    if not stat.S_ISREG(info.st_mode):
        return None
    try:
        with open(path, "rb") as handle:
            return hashlib.file_digest(handle, "sha256").hexdigest()
    except OSError:
        return None


def write_emission(folder: Path, files: Mapping[str, bytes], force: bool) -> list[Path]:
    """Write ``files`` (plain name -> bytes) and their record into ``folder``,
    replacing an earlier emission there whole with ``force``; returns the files
    of the earlier emission that were removed. Refuses (a :class:`CfgplanError`,
    nothing written) when a file cfgplan did not write is in the way."""
    everything = {**files, RECORD: record_text(files).encode("utf-8")}
    if not folder.is_dir():
        write_folder(folder, everything, force)  # a new folder, or an error naming the path
        return []
    earlier = _read_record(folder)
    ours = dict(earlier or {})
    leftovers = [name for name in ours if name not in everything and os.path.lexists(folder / name)]
    foreign: list[str] = []
    present: list[str] = []
    for name in [*everything, *leftovers]:
        path = folder / name
        if not os.path.lexists(path):
            continue
        present.append(name)
        if name == RECORD and earlier is not None:
            continue
        if name not in ours or _current(path) != ours[name]:
            foreign.append(name)
    if foreign:
        shown = ", ".join(foreign)
        raise CfgplanError(
            [
                Diagnostic(
                    "error",
                    f"{folder} holds {shown}, which cfgplan did not write (or which changed "
                    f"since); cfgplan never overwrites or removes such files, even with --force",
                    hint=f"move {'it' if len(foreign) == 1 else 'them'} away, or emit into "
                    f"another folder; nothing was written to {folder}",
                )
            ]
        )
    if present and not force:
        shown = ", ".join(sorted(name for name in present if name != RECORD)) or RECORD
        raise error(
            f"{folder} holds an earlier emission ({shown})",
            hint="pass --force to replace it whole, or emit into another folder",
        )
    write_folder(folder, everything, force=True)
    removed = []
    for name in leftovers:
        path = folder / name
        try:
            path.unlink()
        except OSError as exc:
            raise error(
                f"cannot remove {path}, left from the earlier emission: {exc.strerror}",
                hint=f"the new emission is in place; remove {path} yourself",
            ) from None
        removed.append(path)
    return removed
