"""Hostile and odd input at the command line.

Each case ends with a clear message and exit code, never a traceback, a hang
or a silently wrong answer: outputs that cannot be written (``> /dev/full``),
inputs that are not regular files (``/dev/zero``, a FIFO), memory running out,
old Mac line endings and byte-order marks, non-finite weights, ``-o`` through a
dangling link, and an emission that fails half-way.
"""

from __future__ import annotations

import os
import resource
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from cfgplan.cli.app import _caused_by_memory

ROOT = Path(__file__).resolve().parents[2]
CROSS = ROOT / "domains" / "cross-door"
DOMAIN = str(CROSS / "domain.lisp")
STATE = str(CROSS / "state-6.2.2-step1.lisp")


def cfgplan(
    *args: str, stdout: int | None = subprocess.PIPE, limits: dict[int, int] | None = None
) -> subprocess.CompletedProcess[str]:
    """``python -m cfgplan ARGS`` with optional resource limits; never hangs."""

    def limit() -> None:
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        for which, value in (limits or {}).items():
            resource.setrlimit(which, (value, value))

    return subprocess.run(
        [sys.executable, "-m", "cfgplan", *args],
        cwd=ROOT,
        stdout=stdout,
        stderr=subprocess.PIPE,
        text=True,
        timeout=120,
        preexec_fn=limit,
    )


def clean_failure(done: subprocess.CompletedProcess[str], code: int = 1) -> str:
    assert done.returncode == code, done.stderr
    assert "Traceback" not in done.stderr and "Exception ignored" not in done.stderr
    return done.stderr


# -- item 5: outputs and inputs that are not what they seem -------------------------------


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="no /dev/full here")
@pytest.mark.parametrize(
    "args",
    [("check", DOMAIN), ("plan", DOMAIN, STATE), ("plan", DOMAIN, STATE, "--format", "json")],
    ids=lambda a: " ".join(a[:1] + a[3:]),
)
def test_a_full_output_is_a_clear_error(args: tuple[str, ...]) -> None:
    with open("/dev/full", "w") as full:
        done = cfgplan(*args, stdout=full.fileno())
    err = clean_failure(done)
    assert err.strip() == "cfgplan: error: cannot write the output: No space left on device"


@pytest.mark.skipif(not Path("/dev/zero").exists(), reason="no /dev/zero here")
def test_dev_zero_is_refused_not_read() -> None:
    err = clean_failure(cfgplan("check", "/dev/zero"))
    assert "/dev/zero is a character device; cfgplan reads only regular files" in err


def test_a_fifo_with_no_writer_is_refused_not_waited_for(tmp_path: Path) -> None:
    fifo = tmp_path / "state.lisp"
    os.mkfifo(fifo)
    err = clean_failure(cfgplan("plan", DOMAIN, str(fifo)))
    assert "is a FIFO (named pipe); cfgplan reads only regular files" in err


JOIN = """\
(make-functionality :name '(act ?r) :in '((d ?r)))
(make-functionality :name '(sense ?r ?a ?b ?c ?e) :out '((d ?r)))
(make-config-method :name '(go ?r)
  :precond '((robot ?a) (robot ?b) (robot ?c) (robot ?e))
  :channels '(((local ?r) ?s ?x (d ?r)))
  :body '((?s (sense ?r ?a ?b ?c ?e)) (?x (act ?r))))
"""


@pytest.mark.slow
def test_running_out_of_memory_is_reported(tmp_path: Path) -> None:
    """A method whose preconditions join four robots out of 40 has 2.5 million
    bindings, kept while it is expanded: far more than a 140 MiB address space."""
    (tmp_path / "d.lisp").write_text(JOIN)
    robots = " ".join(f"(robot R{i})" for i in range(40))
    (tmp_path / "s.lisp").write_text(f"(state {robots}) (goal (go R0))")
    limits = {resource.RLIMIT_AS: 140 * 1024 * 1024}
    done = cfgplan("plan", str(tmp_path / "d.lisp"), str(tmp_path / "s.lisp"), limits=limits)
    err = clean_failure(done)
    assert "cfgplan: error: out of memory" in err


def test_a_system_error_is_memory_only_when_caused_by_one() -> None:
    """C code that runs out of memory may raise SystemError while a MemoryError
    is being handled; that is reported as out of memory, other SystemErrors not."""
    try:
        try:
            raise MemoryError
        except MemoryError:
            raise SystemError("returned a result with an exception set")  # noqa: B904
    except SystemError as exc:
        assert _caused_by_memory(exc)
    assert not _caused_by_memory(SystemError("bad argument"))


# -- item 7: line endings and byte-order marks -----------------------------------------------


def test_cr_only_line_endings_are_line_breaks(tmp_path: Path) -> None:
    domain = tmp_path / "mac.lisp"
    domain.write_bytes(
        b"; an old Mac file\r(make-functionality :name '(camera ?r) :out '((image ?r)))\r"
        b"; a second comment\r(make-functionality :name '(sonar ?r) :out '((range ?r)))\r"
    )
    done = cfgplan("check", str(domain))
    assert done.returncode == 0, done.stderr
    assert "2 functionalities" in done.stdout
    bad = tmp_path / "bad.lisp"
    bad.write_bytes(b"; one\r; two\r\n(make-functionality :name '(camera ?r) :bogus 1)\r")
    err = clean_failure(cfgplan("check", str(bad)))
    assert f"{bad}:3:" in err  # \r, \r\n and \n each end a line
    assert "    3 | (make-functionality" in err


def test_a_utf8_byte_order_mark_is_accepted(tmp_path: Path) -> None:
    domain = tmp_path / "bom.lisp"
    domain.write_bytes(b"\xef\xbb\xbf" + Path(DOMAIN).read_bytes())
    state = tmp_path / "bom-state.lisp"
    state.write_bytes(b"\xef\xbb\xbf" + Path(STATE).read_bytes())
    done = cfgplan("plan", str(domain), str(state), "--format", "json")
    assert done.returncode == 0, done.stderr
    assert done.stdout == cfgplan("plan", DOMAIN, STATE, "--format", "json").stdout


def test_other_unicode_line_breaks_do_not_hide_text_in_a_comment(tmp_path: Path) -> None:
    domain = tmp_path / "u2028.lisp"
    functionality = "(make-functionality :name '(camera ?r) :out '((image ?r)))"
    domain.write_text(
        f"{functionality}\n; a note\u2028{functionality.replace('camera', 'sonar')}\n"
    )
    err = clean_failure(cfgplan("check", str(domain)))
    assert f"{domain}:2:9: error: unexpected character '\\u2028'" in err
    assert "line break other than" in err


# -- item 8: weights -------------------------------------------------------------------------


@pytest.mark.parametrize(
    "weight", ["robot=nan", "global=inf", "local=-inf", "robot=1e400", "functionality=NaN"]
)
@pytest.mark.parametrize("command", ["plan", "emit"])
def test_non_finite_weights_are_refused(tmp_path: Path, command: str, weight: str) -> None:
    extra = ["-o", str(tmp_path / "out")] if command == "emit" else ["--format", "json"]
    done = cfgplan(command, DOMAIN, STATE, "--weights", weight, *extra)
    err = clean_failure(done, code=2)
    assert "a weight is a finite number" in err
    assert not (tmp_path / "out").exists()


# -- item 1: -o through a dangling symbolic link --------------------------------------------


@pytest.mark.parametrize(
    "args",
    [
        ("plan", DOMAIN, STATE, "-o", "{link}"),
        ("render", DOMAIN, STATE, "-o", "{link}"),
        ("emit", DOMAIN, STATE, "-o", "{link}"),
        ("plan", DOMAIN, STATE, "--force", "-o", "{link}"),
        ("emit", DOMAIN, STATE, "--force", "-o", "{link}"),
    ],
    ids=lambda a: " ".join(x for x in a if x.startswith("-") or x.isalpha()),
)
def test_output_through_a_dangling_link_is_refused(tmp_path: Path, args: tuple[str, ...]) -> None:
    target = tmp_path / "planted" / "target.dot"
    target.parent.mkdir()
    link = tmp_path / "out.dot"
    link.symlink_to(target)
    err = clean_failure(cfgplan(*(a.format(link=link) for a in args)))
    assert "symbolic link that points nowhere" in err
    assert list(target.parent.iterdir()) == []


# -- item 9: emit writes everything or nothing ---------------------------------------------


@pytest.mark.slow
@pytest.mark.parametrize("lang", ["python", "lisp"])
def test_emit_that_fails_half_way_writes_nothing(tmp_path: Path, lang: str) -> None:
    """With a file size limit (as on a full disk) one file cannot be written: the
    message names that file and the output folder is not created."""
    reference = tmp_path / "reference"
    assert cfgplan("emit", DOMAIN, STATE, "--lang", lang, "-o", str(reference)).returncode == 0
    sizes = {p.name: p.stat().st_size for p in reference.iterdir()}
    limit = min(sizes.values()) + 1
    out = tmp_path / "out"
    done = cfgplan(
        "emit", DOMAIN, STATE, "--lang", lang, "-o", str(out), limits={resource.RLIMIT_FSIZE: limit}
    )
    err = clean_failure(done)
    too_big = [name for name in _order(done, reference, lang) if sizes[name] > limit]
    assert f"cannot write {out / too_big[0]}: File too large" in err
    assert f"nothing was written to {out}" in err
    assert not out.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["reference"]


def _order(done: subprocess.CompletedProcess[str], reference: Path, lang: str) -> list[str]:
    """The order emit writes its files in: robots (sorted as emitted), then the rest."""
    described = (reference / "configuration.txt").read_text()
    robots = [line.rsplit(" -> ", 1)[1] for line in described.splitlines() if " -> " in line]
    return [*robots, *(["run_all.py"] if lang == "python" else []), "configuration.txt"]
