"""``cfgplan emit``: files per robot, the description, and no silent overwrite;
``--force`` replaces an earlier emission whole and never touches the user's files."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from typer.testing import CliRunner

import cfgplan.cli.emit  # noqa: F401  (loads the command module)
from cfgplan.cli.app import app
from cfgplan.diagnostics import CfgplanError
from cfgplan.emission import RECORD
from tests.backends.support import CROSS, DOMAINS, GOLDEN, ROOT, UPDATE

ARGS = [str(DOMAINS / CROSS[0]), str(DOMAINS / CROSS[1])]
LISP = ["emit", *ARGS, "--lang", "lisp"]
"""Where a test needs LISP files (the default is Python)."""


def test_emit_lisp_writes_one_file_per_robot_and_the_description(tmp_path: Path) -> None:
    out = tmp_path / "code"
    result = CliRunner().invoke(app, ["emit", *ARGS, "--lang", "lisp", "-o", str(out)])
    assert result.exit_code == 0, result.output
    assert sorted(p.name for p in out.iterdir()) == [
        RECORD,
        "configuration.txt",
        "emil.lisp",
        "pippi.lisp",
    ]
    emil = (out / "emil.lisp").read_text()
    assert emil.startswith(
        ";; Emil's executable individual configuration (thesis 5.3; cfgplan emit).\n"
    )
    if not UPDATE:  # the code after the comments is the golden of test_lisp
        assert emil.endswith("\n" + (GOLDEN / "cross-door-44" / "emil.lisp").read_text())
    description = (out / "configuration.txt").read_text()
    assert description.startswith("(configuration\n  Functionalities:\n")
    assert "  Cost: 44\n)\n" in description


def test_emit_python_writes_modules_and_run_all(tmp_path: Path) -> None:
    result = CliRunner().invoke(app, ["emit", *ARGS, "--lang", "python", "-o", str(tmp_path)])
    assert result.exit_code == 0, result.output
    # every file it wrote is listed, its record too (it was left out)
    assert result.stderr.splitlines() == [
        f"wrote {tmp_path / name}"
        for name in ("pippi.py", "emil.py", "run_all.py", "configuration.txt", RECORD)
    ]
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        RECORD,
        "configuration.txt",
        "emil.py",
        "pippi.py",
        "run_all.py",
    ]
    if not UPDATE:  # the same text as the golden of test_python
        golden = GOLDEN / "cross-door-44"
        for name in ("pippi.py", "emil.py", "run_all.py"):
            assert (tmp_path / name).read_text() == (golden / name).read_text()


def test_emit_never_overwrites_a_file_it_did_not_write(tmp_path: Path) -> None:
    """A file of the user's in the way is refused, even with --force,
    and named; nothing at all is written."""
    (tmp_path / "emil.lisp").write_text("mine\n")
    for force in ([], ["--force"]):
        result = CliRunner().invoke(app, [*LISP, "-o", str(tmp_path), *force])
        assert result.exit_code == 1
        assert isinstance(result.exception, CfgplanError)
        assert "emil.lisp" in str(result.exception)
        assert "did not write" in str(result.exception)
        assert (tmp_path / "emil.lisp").read_text() == "mine\n"
        assert sorted(p.name for p in tmp_path.iterdir()) == ["emil.lisp"]  # nothing written


def test_emit_refuses_an_earlier_emission_without_force(tmp_path: Path) -> None:
    first = CliRunner().invoke(app, [*LISP, "-o", str(tmp_path)])
    assert first.exit_code == 0, first.output
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    again = CliRunner().invoke(app, ["emit", *ARGS, "--lang", "python", "-o", str(tmp_path)])
    assert again.exit_code == 1
    assert isinstance(again.exception, CfgplanError)
    (refusal,) = again.exception.diagnostics
    assert refusal.message.endswith(
        "holds an earlier emission (configuration.txt, emil.lisp, pippi.lisp)"
    )
    assert refusal.hint is not None and "--force" in refusal.hint
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before


def test_emit_force_replaces_the_earlier_emission_whole(tmp_path: Path) -> None:
    """LISP then Python into one folder with --force: no .lisp robot
    file of the earlier emission remains; the user's own notes stay."""
    assert CliRunner().invoke(app, [*LISP, "-o", str(tmp_path)]).exit_code == 0
    (tmp_path / "notes.txt").write_text("my notes\n")
    result = CliRunner().invoke(
        app, ["emit", *ARGS, "--lang", "python", "-o", str(tmp_path), "--force"]
    )
    assert result.exit_code == 0, result.output
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        [RECORD, "configuration.txt", "emil.py", "pippi.py", "run_all.py", "notes.txt"]
    )
    assert f"removed {tmp_path / 'emil.lisp'} (from the earlier emission)" in result.output
    assert (tmp_path / "notes.txt").read_text() == "my notes\n"


def test_emit_force_keeps_an_emitted_file_the_user_changed(tmp_path: Path) -> None:
    """An emitted file edited since is the user's now: --force refuses to remove it."""
    assert CliRunner().invoke(app, [*LISP, "-o", str(tmp_path)]).exit_code == 0
    edited = tmp_path / "emil.lisp"
    edited.write_text(edited.read_text() + ";; my change\n")
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    result = CliRunner().invoke(
        app, ["emit", *ARGS, "--lang", "python", "-o", str(tmp_path), "--force"]
    )
    assert result.exit_code == 1
    assert "emil.lisp" in str(result.exception) and "pippi.lisp" not in str(result.exception)
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before


def test_emit_is_deterministic(tmp_path: Path) -> None:
    for name in ("a", "b"):
        result = CliRunner().invoke(
            app, ["emit", *ARGS, "--lang", "python", "-o", str(tmp_path / name)]
        )
        assert result.exit_code == 0
    for f in (tmp_path / "a").iterdir():
        assert f.read_bytes() == (tmp_path / "b" / f.name).read_bytes()


def test_emit_force_again_gives_the_same_files(tmp_path: Path) -> None:
    """Replacing an emission by the same one is allowed with --force, byte for byte."""
    assert CliRunner().invoke(app, ["emit", *ARGS, "-o", str(tmp_path)]).exit_code == 0
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    result = CliRunner().invoke(app, ["emit", *ARGS, "-o", str(tmp_path), "--force"])
    assert result.exit_code == 0, result.output
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before


def test_emit_a_rank_that_does_not_exist_exits_3(tmp_path: Path) -> None:
    result = CliRunner().invoke(app, ["emit", *ARGS, "--rank", "3", "-o", str(tmp_path)])
    assert result.exit_code == 3
    assert list(tmp_path.iterdir()) == []


def test_emit_without_lang_writes_runnable_python(tmp_path: Path) -> None:
    """Without --lang, emit wrote LISP, which nothing here runs; now
    it writes the Python of ``--lang python`` (byte for byte), and
    ``run_all.py`` runs the configuration."""
    out = tmp_path / "out"
    result = CliRunner().invoke(app, ["emit", *ARGS, "-o", str(out)])
    assert result.exit_code == 0, result.output
    assert sorted(p.name for p in out.iterdir()) == [
        RECORD,
        "configuration.txt",
        "emil.py",
        "pippi.py",
        "run_all.py",
    ]
    assert (out / "configuration.txt").read_text().endswith(";;   Emil -> emil.py\n")
    if not UPDATE:
        for name in ("pippi.py", "emil.py", "run_all.py"):
            assert (out / name).read_text() == (GOLDEN / "cross-door-44" / name).read_text()
    impl = ROOT / "examples" / "cross-door" / "impl.py"
    command = [sys.executable, str(out / "run_all.py"), "--impl", str(impl), "--rate", "0"]
    ran = subprocess.run(
        [*command, "--cycles", "3"], capture_output=True, text=True, cwd=ROOT, timeout=60
    )
    assert ran.returncode == 0, ran.stderr
    assert "cross-door(Pippi, Door1): ran in 2 of 3 cycles" in ran.stdout
