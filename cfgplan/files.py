"""Reading the user's files and writing cfgplan's, safely.

Reading (:func:`read_source`): only a regular file is read, never a FIFO, a
device (``/dev/zero``), a socket or a directory, and at most
:data:`MAX_SOURCE_BYTES` of it; the file is opened without blocking, so a FIFO
with no writer cannot hang cfgplan.

Writing (:func:`write_file`, :func:`write_folder`): an output file that is a
symbolic link (dangling or not) or not a regular file is refused, and so is an
output folder that is a dangling link (a link to an existing folder is the
user's way to put the output elsewhere, and is followed); cfgplan never
writes through a link to a file. An existing file is replaced only with
``--force``.
Everything is written to a temporary file or folder beside the target first
and moved into place with a rename, so a failed write (a full disk) leaves the
target as it was, and the message names the file that could not be written.
File names inside an output folder must be single path components; names
that come from the input go through :mod:`cfgplan.safe_names` first.
"""

from __future__ import annotations

import contextlib
import os
import secrets
import shutil
import stat
from collections.abc import Mapping
from dataclasses import replace
from pathlib import Path

from cfgplan.diagnostics import CfgplanError, error

__all__ = ["MAX_SOURCE_BYTES", "check_target", "read_source", "write_file", "write_folder"]

MAX_SOURCE_BYTES = 4 * 1024 * 1024
"""The largest domain or state file cfgplan reads: 4 MiB, 500 times the thesis's
largest; reading one that size takes about 40 s and 1.5 GiB (Lark, positions on)."""

_KINDS = (
    (stat.S_ISDIR, "a directory"),
    (stat.S_ISFIFO, "a FIFO (named pipe)"),
    (stat.S_ISCHR, "a character device"),
    (stat.S_ISBLK, "a block device"),
    (stat.S_ISSOCK, "a socket"),
)


def _kind(mode: int) -> str:
    for test, name in _KINDS:
        if test(mode):
            return name
    return "not a regular file"


def read_source(path: str | Path, limit: int = MAX_SOURCE_BYTES) -> bytes:
    """The bytes of the regular file ``path``; a CfgplanError naming the file when
    it is missing, unreadable, not a regular file, or larger than ``limit``."""
    name = str(path)
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_BINARY", 0)
    try:
        fd = os.open(path, flags)
    except FileNotFoundError:
        raise error(f"no such file: {name}") from None
    except OSError as exc:
        raise error(f"cannot read {name}: {exc.strerror}") from None
    try:
        mode = os.fstat(fd).st_mode
        if stat.S_ISDIR(mode):
            raise error(f"{name} is a directory, not a file")
        if not stat.S_ISREG(mode):
            raise error(
                f"{name} is {_kind(mode)}; cfgplan reads only regular files",
                hint="save the text to a file and give its path",
            )
        chunks: list[bytes] = []
        size = 0
        while size <= limit:
            chunk = os.read(fd, min(1 << 20, limit + 1 - size))
            if not chunk:
                break
            chunks.append(chunk)
            size += len(chunk)
        data = b"".join(chunks)
    except OSError as exc:
        raise error(f"cannot read {name}: {exc.strerror}") from None
    finally:
        os.close(fd)
    if len(data) > limit:
        raise error(
            f"{name} is larger than {limit // (1024 * 1024)} MiB; "
            "cfgplan does not read files that large",
            hint="domains and states are text files of a few kilobytes",
        )
    return data


def check_target(path: Path, force: bool) -> None:
    """Refuse to write ``path`` when it is a symbolic link, not a regular file,
    or an existing file without ``force``."""
    try:
        info = path.lstat()
    except FileNotFoundError:
        return
    except OSError as exc:
        raise error(f"cannot write {path}: {exc.strerror}") from None
    if stat.S_ISLNK(info.st_mode):
        dangling = "" if path.exists() else " that points nowhere"
        raise error(
            f"{path} is a symbolic link{dangling}; cfgplan does not write through links",
            hint="give the path of the file itself, or remove the link",
        )
    if not stat.S_ISREG(info.st_mode):
        raise error(f"{path} is {_kind(info.st_mode)}; cfgplan writes only regular files")
    if not force:
        raise error(f"{path} exists; pass --force to overwrite it")


def _temporary(folder: Path, stem: str) -> Path:
    """A new, unused name in ``folder`` for a temporary file or folder."""
    return folder / f".{stem[:40]}.cfgplan-{secrets.token_hex(4)}"


def _write_new(path: Path, data: bytes, shown: Path, mode: int | None = None) -> None:
    """Create ``path`` (which must not exist) holding ``data``; errors name ``shown``."""
    try:
        with open(path, "xb") as handle:
            handle.write(data)
            handle.flush()
        if mode is not None:
            os.chmod(path, mode)
    except OSError as exc:
        raise error(f"cannot write {shown}: {exc.strerror}") from None


def write_file(path: Path, data: bytes, force: bool) -> None:
    """Write ``data`` to ``path`` in one step: a temporary file beside it, then a
    rename; ``path`` is left as it was when anything fails."""
    check_target(path, force)
    folder = path.parent
    mode = None
    with contextlib.suppress(OSError):
        mode = stat.S_IMODE(path.stat().st_mode)  # an overwritten file keeps its mode
    temporary = _temporary(folder, path.name)
    try:
        _write_new(temporary, data, path, mode)
        os.replace(temporary, path)
    except OSError as exc:
        raise error(f"cannot write {path}: {exc.strerror}") from None
    finally:
        with contextlib.suppress(OSError):
            temporary.unlink()


def _plain(name: str) -> None:
    if not name or name in (".", "..") or "/" in name or "\\" in name or "\0" in name:
        raise ValueError(f"not a plain file name: {name!r}")


def write_folder(folder: Path, files: Mapping[str, bytes], force: bool) -> None:
    """Write ``files`` (plain name -> bytes) into ``folder``, all or nothing as
    far as the file system allows.

    A new folder is written whole under a temporary name and renamed into
    place. Into an existing folder, every file is first written whole to a
    temporary folder inside it, then each is moved into place by a rename; a
    file already there is replaced only with ``force``.
    """
    for name in files:
        _plain(name)
    try:
        info = folder.lstat()
    except FileNotFoundError:
        info = None
    except OSError as exc:
        raise error(f"cannot write to {folder}: {exc.strerror}") from None
    if info is not None and stat.S_ISLNK(info.st_mode) and not folder.exists():
        raise error(
            f"{folder} is a symbolic link that points nowhere; cfgplan does not write through it",
            hint="give the path of an existing folder or of one to create",
        )
    if info is not None and not folder.is_dir():
        raise error(f"{folder} exists and is not a directory")
    if info is None:
        _new_folder(folder, files)
        return
    problems: list[CfgplanError] = []
    existing: list[str] = []
    for name in files:
        try:
            check_target(folder / name, force=True)
        except CfgplanError as exc:
            problems.append(exc)
        if (folder / name).exists():
            existing.append(name)
    if problems:
        raise CfgplanError([d for p in problems for d in p.diagnostics])
    if existing and not force:
        raise error(f"{folder} already holds {', '.join(existing)}; pass --force to overwrite")
    _into_folder(folder, files)


def _stage(where: Path, stem: str, folder: Path, files: Mapping[str, bytes]) -> Path:
    """A new temporary folder in ``where`` holding ``files`` whole, each with the
    mode of the file it will replace in ``folder``; on failure nothing is left
    and the error names the file of ``folder`` that could not be written."""
    temporary = _temporary(where, stem)
    try:
        temporary.mkdir()
    except OSError as exc:
        raise error(f"cannot write to {folder}: {exc.strerror}") from None
    try:
        for name, data in files.items():
            mode = None
            with contextlib.suppress(OSError):
                mode = stat.S_IMODE((folder / name).stat().st_mode)
            _write_new(temporary / name, data, folder / name, mode)
    except CfgplanError as exc:
        shutil.rmtree(temporary, ignore_errors=True)
        raise _nothing_written(exc, folder) from None
    return temporary


def _new_folder(folder: Path, files: Mapping[str, bytes]) -> None:
    try:
        folder.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise error(f"cannot create {folder.parent}: {exc.strerror}") from None
    temporary = _stage(folder.parent, folder.name, folder, files)
    try:
        os.rename(temporary, folder)
    except OSError as exc:
        shutil.rmtree(temporary, ignore_errors=True)
        raise _nothing_written(error(f"cannot create {folder}: {exc.strerror}"), folder) from None


def _into_folder(folder: Path, files: Mapping[str, bytes]) -> None:
    temporary = _stage(folder, "emit", folder, files)
    try:
        for name in files:
            try:
                os.replace(temporary / name, folder / name)
            except OSError as exc:
                raise error(f"cannot write {folder / name}: {exc.strerror}") from None
    finally:
        shutil.rmtree(temporary, ignore_errors=True)


def _nothing_written(exc: CfgplanError, folder: Path) -> CfgplanError:
    """``exc`` with a hint that the output folder was left as it was."""
    hint = f"nothing was written to {folder}"
    return CfgplanError([d if d.hint else replace(d, hint=hint) for d in exc.diagnostics])
