"""``cfgplan emit``: files per robot, the description, and no silent overwrite."""

from __future__ import annotations

from pathlib import Path

from typer.testing import CliRunner

import cfgplan.cli.emit  # noqa: F401  (registers the command)
from cfgplan.cli.app import app
from cfgplan.diagnostics import CfgplanError
from tests.backends.support import CROSS, DOMAINS, GOLDEN, UPDATE

ARGS = [str(DOMAINS / CROSS[0]), str(DOMAINS / CROSS[1])]


def test_emit_lisp_writes_one_file_per_robot_and_the_description(tmp_path: Path) -> None:
    out = tmp_path / "code"
    result = CliRunner().invoke(app, ["emit", *ARGS, "--lang", "lisp", "-o", str(out)])
    assert result.exit_code == 0, result.output
    assert sorted(p.name for p in out.iterdir()) == ["configuration.txt", "emil.lisp", "pippi.lisp"]
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
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "configuration.txt",
        "emil.py",
        "pippi.py",
        "run_all.py",
    ]
    if not UPDATE:  # the same text as the golden of test_python
        golden = GOLDEN / "cross-door-44"
        for name in ("pippi.py", "emil.py", "run_all.py"):
            assert (tmp_path / name).read_text() == (golden / name).read_text()


def test_emit_refuses_to_overwrite_without_force(tmp_path: Path) -> None:
    (tmp_path / "emil.lisp").write_text("mine\n")
    result = CliRunner().invoke(app, ["emit", *ARGS, "-o", str(tmp_path)])
    assert result.exit_code == 1
    assert isinstance(result.exception, CfgplanError)
    assert "emil.lisp" in str(result.exception) and "--force" in str(result.exception)
    assert (tmp_path / "emil.lisp").read_text() == "mine\n"
    assert not (tmp_path / "pippi.lisp").exists()  # nothing written at all
    result = CliRunner().invoke(app, ["emit", *ARGS, "-o", str(tmp_path), "--force"])
    assert result.exit_code == 0, result.output
    assert (tmp_path / "emil.lisp").read_text() != "mine\n"


def test_emit_is_deterministic(tmp_path: Path) -> None:
    for name in ("a", "b"):
        result = CliRunner().invoke(
            app, ["emit", *ARGS, "--lang", "python", "-o", str(tmp_path / name)]
        )
        assert result.exit_code == 0
    for f in (tmp_path / "a").iterdir():
        assert f.read_bytes() == (tmp_path / "b" / f.name).read_bytes()


def test_emit_a_rank_that_does_not_exist_exits_3(tmp_path: Path) -> None:
    result = CliRunner().invoke(app, ["emit", *ARGS, "--rank", "3", "-o", str(tmp_path)])
    assert result.exit_code == 3
    assert list(tmp_path.iterdir()) == []
