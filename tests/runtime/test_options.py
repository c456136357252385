"""``cfgplan run`` and the emitted programs agree on their options (5.2, 5.3):
the same flags, metavariables, defaults, help and the same verdict, in the
same words, on a bad value (:mod:`cfgplan.runtime.options`)."""

from __future__ import annotations

import argparse
from typing import Any

import pytest
import typer

from cfgplan.cli import commands  # noqa: F401  (loads every command module)
from cfgplan.cli.app import app
from cfgplan.runtime.main import parser_of
from cfgplan.runtime.options import (
    LAUNCHED,
    NETWORK_OPTIONS,
    RUN_OPTIONS,
    UNTIL,
    Option,
    how_long,
    launched,
)


def _run_params() -> dict[str, Any]:
    group = typer.main.get_command(app)
    assert isinstance(group, typer.core.TyperGroup)
    command = group.get_command(typer.Context(group, info_name="cfgplan"), "run")
    assert command is not None
    return {opt: p for p in command.params for opt in getattr(p, "opts", [])}


def _actions(parser: argparse.ArgumentParser) -> dict[str, argparse.Action]:
    return {opt: a for a in parser._actions for opt in a.option_strings}


ROBOT = parser_of("Run Emil's part.", network=True)
SOCIETY = parser_of("Run Pippi, Emil.", network=False)


@pytest.mark.parametrize("option", RUN_OPTIONS + NETWORK_OPTIONS, ids=lambda o: o.flag)
def test_the_same_flags_defaults_and_help(option: Option[Any]) -> None:
    ours = _run_params()[option.flag]
    assert ours.help == option.help
    assert ours.metavar == option.metavar
    programs = [ROBOT] + ([SOCIETY] if option in RUN_OPTIONS else [])
    for parser in programs:
        theirs = _actions(parser)[option.flag]
        assert theirs.help == option.help.replace("%", "%%")
        assert theirs.metavar == option.metavar
        assert theirs.default == (option.default if option.metavar else False)
    if option.default not in (None, [], False):  # cfgplan run's own default, as given
        assert ours.default == option.default
    assert option.dest in vars(ROBOT.parse_args(["--impl", "x"]))


def test_both_run_until_interrupted_by_default() -> None:
    defaults = ROBOT.parse_args(["--impl", "x"])
    assert (defaults.cycles, defaults.duration) == (0, None)
    assert how_long(defaults.cycles, defaults.duration) == "until interrupted (Ctrl-C)"
    assert how_long(3, 2.5) == "3 cycle(s) or 2.5 s"
    assert UNTIL in (ROBOT.description or "") and UNTIL in (SOCIETY.description or "")
    group = typer.main.get_command(app)
    assert isinstance(group, typer.core.TyperGroup)
    run = group.get_command(typer.Context(group, info_name="cfgplan"), "run")
    assert run is not None and run.help is not None
    assert "Runs until interrupted (Ctrl-C or SIGTERM)" in run.help


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--rate", "-1"], "-1: must be at least 0"),
        (["--rate", "nan"], "nan: must be a finite number"),
        (["--cycles", "two"], "'two' is not a whole number"),
        (["--duration", "0"], "0: must be more than 0"),
        (["--stale-periods", "0"], "0: must be more than 0"),
        (["--budget", "inf"], "inf: must be a finite number"),
        (["--inject", "boom"], "not a fault I can inject"),
        (["--listen", "7447"], "an endpoint is PROTOCOL/ADDRESS"),
        (["--lease", "0"], "0: must be more than 0"),
    ],
)
def test_a_bad_value_is_refused_alike(
    args: list[str], message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(SystemExit) as exited:
        ROBOT.parse_args(["--impl", "x", *args])
    assert exited.value.code == 2
    assert message in capsys.readouterr().err
    param = _run_params()[args[0]]
    value = args[1:] if param.multiple else args[1]
    with pytest.raises(typer.BadParameter) as refused:
        param.process_value(typer.Context(typer.main.get_command(app)), value)
    assert message in refused.value.format_message()


def test_a_robot_the_launch_started_does_not_claim_ctrl_c(monkeypatch: pytest.MonkeyPatch) -> None:
    """The robots of cfgplan launch run in sessions of their own: Ctrl-C reaches
    the launch, which stops them. They said "until interrupted (Ctrl-C)"."""
    import subprocess

    from cfgplan.runtime import spawn

    seen: list[dict[str, str]] = []

    def popen(*args: object, **kwargs: object) -> object:
        env = kwargs["env"]
        assert isinstance(env, dict)
        seen.append(env)
        raise OSError("not started in this test")

    monkeypatch.setattr(subprocess, "Popen", popen)
    launch = spawn.Launch([spawn.RobotCommand("Pippi", ("run",), "127.0.0.1", spawn.free_port())])
    with pytest.raises(OSError):
        launch.start()
    assert seen and seen[0][LAUNCHED] == "1"
    monkeypatch.setenv(LAUNCHED, "1")
    assert launched() and how_long(0, None) == "until the launch stops it"
    assert how_long(5, None) == "5 cycle(s)"
    monkeypatch.delenv(LAUNCHED)
    assert how_long(0, None) == "until interrupted (Ctrl-C)"
