"""``cfgplan run``: the configuration executed in process (chapter 5)."""

from __future__ import annotations

from typer.testing import CliRunner

import cfgplan.cli.run  # noqa: F401  (registers the command)
from cfgplan.cli.app import app
from tests.backends.support import CROSS, DOMAINS, EXAMPLE_IMPL, cross_door_44

ARGS = [str(DOMAINS / CROSS[0]), str(DOMAINS / CROSS[1])]


def test_run_prints_what_cross_door_received() -> None:
    _, config = cross_door_44()
    (label,) = [f.label for f in config.functionalities if f.name == "cross-door"]
    result = CliRunner().invoke(app, ["run", *ARGS, "--impl", str(EXAMPLE_IMPL), "--cycles", "3"])
    assert result.exit_code == 0, result.output
    lines = result.output.splitlines()
    assert (
        lines[0]
        == "Configuration rank 1, cost 44, for do-cross-door(Pippi, Door1): Pippi, Emil; 3 cycle(s)"
    )
    received = [line for line in lines if " received " in line]
    assert [line.split(":")[0] for line in received] == ["cycle 2", "cycle 3"]
    assert received[0].startswith(
        f"cycle 2: Pippi {label} cross-door(Pippi, Door1) received pos(Pippi, Door1) = ("
    )
    assert f"Pippi {label} cross-door(Pippi, Door1): ran in 2 of 3 cycles" in lines


def test_run_trace_shows_every_call_and_rank_2_runs_too() -> None:
    """Rank 2 (cost 47, cameras only, Fig. 6.4) runs on the same implementations."""
    result = CliRunner().invoke(
        app, ["run", *ARGS, "--impl", str(EXAMPLE_IMPL), "--rank", "2", "--cycles", "2", "--trace"]
    )
    assert result.exit_code == 0, result.output
    assert "cost 47" in result.output.splitlines()[0]
    assert "measure-robot-orient-camera(Emil, Pippi) read angle(Emil, Pippi) = " in result.output
    assert (
        "cross-door(Pippi, Door1) waits for pos(Pippi, Door1), orient(Pippi, Door1)"
        in result.output
    )


def test_run_without_an_implementation_fails_clearly() -> None:
    carry = [str(DOMAINS / "carry-bar/domain.lisp"), str(DOMAINS / "carry-bar/state-6.3.2.lisp")]
    result = CliRunner().invoke(app, ["run", *carry, "--impl", str(EXAMPLE_IMPL)])
    assert result.exit_code == 1
    message = str(result.exception)
    # every missing one at once, before anything runs
    assert (
        "no implementation of functionalities calc-robot-speed-diff, laser, lead-robot, " in message
    )
    assert "meas-robot-angle-dist-laser, stalk-robot in " in message


def test_run_a_rank_that_does_not_exist_exits_3() -> None:
    result = CliRunner().invoke(app, ["run", *ARGS, "--impl", str(EXAMPLE_IMPL), "--rank", "9"])
    assert result.exit_code == 3
