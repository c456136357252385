"""Reading the user's files and writing cfgplan's (cfgplan/files.py)."""

from __future__ import annotations

import os
import resource
import signal
import subprocess
import sys
import threading
from pathlib import Path

import pytest

from cfgplan.diagnostics import CfgplanError
from cfgplan.files import MAX_SOURCE_BYTES, read_source, write_file, write_folder


def _message(exc: pytest.ExceptionInfo[CfgplanError]) -> str:
    return "; ".join(d.message for d in exc.value.diagnostics)


# -- reading ------------------------------------------------------------------------


def test_a_fifo_without_writer_is_refused_at_once(tmp_path: Path) -> None:
    fifo = tmp_path / "state.lisp"
    os.mkfifo(fifo)
    outcome: list[BaseException | bytes] = []
    reader = threading.Thread(target=lambda: outcome.append(_catch(fifo)), daemon=True)
    reader.start()
    reader.join(timeout=10)
    if reader.is_alive():  # unblock the thread, then fail
        os.close(os.open(fifo, os.O_WRONLY | os.O_NONBLOCK))
        pytest.fail("reading a FIFO with no writer blocked")
    (result,) = outcome
    assert isinstance(result, CfgplanError)
    assert "is a FIFO (named pipe); cfgplan reads only regular files" in str(result)


def _catch(path: Path) -> BaseException | bytes:
    try:
        return read_source(path)
    except BaseException as exc:
        return exc


@pytest.mark.parametrize(("path", "kind"), [("/dev/zero", "character device"), ("/", "directory")])
def test_devices_and_directories_are_refused(path: str, kind: str) -> None:
    if not Path(path).exists():
        pytest.skip(f"{path} does not exist here")
    with pytest.raises(CfgplanError) as caught:
        read_source(path)
    assert kind in _message(caught)


def test_a_file_past_the_cap_is_refused_without_reading_it_all(tmp_path: Path) -> None:
    big = tmp_path / "big.lisp"
    with open(big, "wb") as handle:
        handle.truncate(MAX_SOURCE_BYTES + 1)  # sparse: no disk used
    with pytest.raises(CfgplanError) as caught:
        read_source(big)
    assert "larger than 4 MiB" in _message(caught)
    small = tmp_path / "small.lisp"
    small.write_bytes(b"x" * 100)
    assert read_source(small, limit=100) == b"x" * 100
    with pytest.raises(CfgplanError):
        read_source(small, limit=99)


def test_missing_file() -> None:
    with pytest.raises(CfgplanError) as caught:
        read_source("/nonexistent/domain.lisp")
    assert _message(caught) == "no such file: /nonexistent/domain.lisp"


# -- writing one file -----------------------------------------------------------------


def test_a_dangling_symlink_is_not_written_through(tmp_path: Path) -> None:
    target = tmp_path / "elsewhere" / "planted.txt"
    target.parent.mkdir()
    link = tmp_path / "out.dot"
    link.symlink_to(target)
    for force in (False, True):
        with pytest.raises(CfgplanError) as caught:
            write_file(link, b"digraph {}\n", force)
        assert "symbolic link that points nowhere" in _message(caught)
    assert not target.exists()
    assert link.is_symlink()


def test_a_symlink_to_a_file_is_not_written_through(tmp_path: Path) -> None:
    target = tmp_path / "precious.txt"
    target.write_text("precious\n")
    link = tmp_path / "out.dot"
    link.symlink_to(target)
    with pytest.raises(CfgplanError) as caught:
        write_file(link, b"digraph {}\n", True)
    assert "is a symbolic link; cfgplan does not write through links" in _message(caught)
    assert target.read_text() == "precious\n"


def test_write_file_replaces_only_with_force_and_keeps_the_mode(tmp_path: Path) -> None:
    path = tmp_path / "plan.json"
    write_file(path, b"one\n", False)
    path.chmod(0o640)
    with pytest.raises(CfgplanError):
        write_file(path, b"two\n", False)
    assert path.read_bytes() == b"one\n"
    write_file(path, b"two\n", True)
    assert path.read_bytes() == b"two\n"
    assert path.stat().st_mode & 0o777 == 0o640
    assert [p.name for p in tmp_path.iterdir()] == ["plan.json"]  # no temporary left


def test_a_device_is_not_an_output(tmp_path: Path) -> None:
    with pytest.raises(CfgplanError) as caught:
        write_file(Path("/dev/null"), b"x", True)
    assert "character device; cfgplan writes only regular files" in _message(caught)


# -- writing a folder (emit) ------------------------------------------------------------


def test_write_folder_creates_the_folder_whole(tmp_path: Path) -> None:
    out = tmp_path / "a" / "out"
    write_folder(out, {"emil.py": b"1\n", "pippi.py": b"2\n"}, False)
    assert sorted(p.name for p in out.iterdir()) == ["emil.py", "pippi.py"]
    assert [p.name for p in (tmp_path / "a").iterdir()] == ["out"]


def test_write_folder_refuses_a_dangling_symlink(tmp_path: Path) -> None:
    link = tmp_path / "out"
    link.symlink_to(tmp_path / "nowhere")
    with pytest.raises(CfgplanError) as caught:
        write_folder(link, {"emil.py": b"1\n"}, True)
    assert "symbolic link that points nowhere" in _message(caught)
    assert not (tmp_path / "nowhere").exists()


def test_write_folder_refuses_names_that_are_not_plain(tmp_path: Path) -> None:
    for name in ("../x.py", "/x.py", "..", "a\\b", ""):
        with pytest.raises(ValueError):
            write_folder(tmp_path / "out", {name: b""}, True)
    assert not (tmp_path / "out").exists()


def _limited_fsize(limit: int) -> None:
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a write past the limit fails with EFBIG
    resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))


_WRITE = """
import sys
from pathlib import Path
from cfgplan.diagnostics import CfgplanError
from cfgplan.files import write_folder
try:
    write_folder(Path(sys.argv[1]), {"a.py": b"a" * 100, "b.py": b"b" * 5000, "c.py": b"c"}, True)
except CfgplanError as exc:
    print(exc.diagnostics[0].message, "|", exc.diagnostics[0].hint)
    sys.exit(1)
"""


@pytest.mark.parametrize("exists", [False, True])
def test_a_failed_write_leaves_the_folder_as_it_was(tmp_path: Path, exists: bool) -> None:
    """The second file cannot be written (file size limit, as on a full disk):
    the message names it, and the output folder is as it was."""
    out = tmp_path / "out"
    if exists:
        out.mkdir()
        (out / "a.py").write_text("old\n")
    done = subprocess.run(
        [sys.executable, "-c", _WRITE, str(out)],
        capture_output=True,
        text=True,
        preexec_fn=lambda: _limited_fsize(1000),
        timeout=60,
    )
    assert done.returncode == 1, done.stderr
    assert done.stdout.startswith(f"cannot write {out / 'b.py'}: File too large")
    assert f"nothing was written to {out}" in done.stdout
    if exists:
        assert [p.name for p in out.iterdir()] == ["a.py"]
        assert (out / "a.py").read_text() == "old\n"
    else:
        assert not out.exists()
    assert [p.name for p in tmp_path.iterdir()] == (["out"] if exists else [])
