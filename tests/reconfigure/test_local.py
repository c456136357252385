"""``cfgplan run`` reconfiguring a society in one process (5.5; 6.2.2 step 3, 6.3.2).

The issue's "done when": the cross-door run of 6.2.2 step 2 with Emil's
compass failing at cycle 20 shows 44 running, the failure, the switch to the
camera configuration (47, Fig. 6.4 bottom) and cross-door receiving the door
again within three cycles; carry-a-bar 6.3.2 switches 33 -> 45 when the
laser fails and does not flap when it returns.
"""

from __future__ import annotations

import json
import textwrap
import threading
from pathlib import Path

import pytest
from typer.testing import CliRunner

import cfgplan.cli.run  # noqa: F401  (loads the command module)
from cfgplan.cli.app import app
from tests.backends.support import DOMAINS, EXAMPLE_IMPL, ROOT

STEP2 = [
    str(DOMAINS / "cross-door/domain.lisp"),
    str(DOMAINS / "cross-door/state-6.2.2-step2.lisp"),
]
CARRY = [str(DOMAINS / "carry-bar/domain.lisp"), str(DOMAINS / "carry-bar/state-6.3.2.lisp")]
CARRY_IMPL = ROOT / "examples" / "carry-bar" / "impl.py"
Record = dict[str, object]


def _run(args: list[str], trace: Path, *faults: str) -> tuple[int, str, list[Record]]:
    """``cfgplan run ARGS --trace TRACE --inject FAULT...``: exit code, output, trace."""
    injected = [arg for fault in faults for arg in ("--inject", fault)]
    result = CliRunner().invoke(app, ["run", *args, "--trace", str(trace), *injected])
    lines = [json.loads(x) for x in trace.read_text().splitlines()]
    return result.exit_code, result.output, lines


def _events(trace: list[Record], kind: str) -> list[Record]:
    return [r for r in trace if r["event"] == kind]


def _action(trace: list[Record], name: str) -> list[Record]:
    return [r for r in trace if r["event"] == "call" and r["functionality"] == name]


def _gap(calls: list[Record], after: int) -> int:
    """Cycles from ``after`` on in which the action got no data, before it got some."""
    later = [c for c in calls if int(c["cycle"]) >= after]  # type: ignore[call-overload]
    for missed, call in enumerate(later):
        if call["status"] == "ran":
            return missed
    raise AssertionError("the action never received data again")


@pytest.mark.slow
def test_the_compass_of_step_3_fails_and_the_camera_configuration_takes_over(
    tmp_path: Path,
) -> None:
    """The issue's command line, as given (10 cycles a second, 60 cycles)."""
    code, output, trace = _run(
        [*STEP2, "--impl", str(EXAMPLE_IMPL), "--cycles", "60"],
        tmp_path / "T",
        "fail compass(Emil) at cycle 20",
    )
    assert code == 0, output
    assert "cost 44" in output.splitlines()[0]
    ran = _action(trace, "compass")
    assert {r["status"] for r in ran if int(r["cycle"]) < 20} == {"ran"}  # type: ignore[call-overload]
    (failure,) = _events(trace, "failure")
    assert (failure["resource"], failure["how"], failure["cycle"]) == (
        "compass(Emil)",
        "injected",
        20,
    )
    assert failure["withdrawn"] == ["(compass Emil)"]
    (switch,) = _events(trace, "switch")
    assert (switch["from_cost"], switch["to_cost"], switch["source"]) == (44, 47, "fallback")
    stopped = switch["stopped"]["functionalities"]  # type: ignore[index]
    started = switch["started"]["functionalities"]  # type: ignore[index]
    kept = switch["kept"]["functionalities"]  # type: ignore[index]
    assert [s.split(": ")[1] for s in stopped] == [
        "measure-robot-orient-compass(Pippi, Emil)",
        "compass(Pippi)",
        "compass(Emil)",
    ]
    assert sorted(s.split(": ")[1] for s in started) == [
        "camera(Emil)",
        "measure-robot-angle(Emil, Pippi)",
        "measure-robot-angle(Pippi, Emil)",
        "measure-robot-orient-camera(Pippi, Emil)",
    ]
    assert (
        "F3: cross-door(Emil, Door1)" in kept and "F7: transform-info(Pippi, Emil, Door1)" in kept
    )
    assert 0 <= switch["latency"] < 1.0  # type: ignore[operator]
    installs = _events(trace, "install")
    assert sorted(i["robot"] for i in installs) == ["Emil", "Pippi"]  # type: ignore[type-var]
    cross = _action(trace, "cross-door")
    assert _gap(cross, 21) <= 3
    before = next(c for c in cross if c["cycle"] == 19 and c["status"] == "ran")
    after = [c for c in cross if int(c["cycle"]) > 21 and c["status"] == "ran"]  # type: ignore[call-overload]
    assert len(after) >= 35  # it keeps receiving until the end
    for (_, a), (_, b) in zip(
        ((i["data"], i["value"]) for i in before["inputs"]),  # type: ignore[attr-defined]
        ((i["data"], i["value"]) for i in after[-1]["inputs"]),  # type: ignore[attr-defined]
        strict=True,
    ):
        assert b == pytest.approx(a)  # the cameras see the door where the compasses did
    assert not [
        r
        for r in trace
        if r["event"] == "call" and r["functionality"] == "compass" and int(r["cycle"]) > 20
    ]  # type: ignore[call-overload]
    assert "switch 1 (compass(Emil) failed): cost 44 -> 47 (fallback)" in output


@pytest.mark.slow
def test_carry_bar_switches_to_45_when_the_laser_fails_and_back_once(tmp_path: Path) -> None:
    """6.3.2: laser fails -> 45 (Fig. 6.8 bottom). It comes back, fails again
    while on probation and comes back for good: one switch back, after the hold."""
    code, output, trace = _run(
        [*CARRY, "--impl", str(CARRY_IMPL), "--rate", "20", "--cycles", "110", "--hold", "2"],
        tmp_path / "T",
        "fail laser(Emil) at cycle 10",
        "recover laser(Emil) at cycle 15",
        "fail laser(Emil) at cycle 20",
        "recover laser(Emil) at cycle 25",
    )
    assert code == 0, output
    switches = _events(trace, "switch")
    assert [(s["from_cost"], s["to_cost"]) for s in switches] == [(33, 45), (45, 33)]
    (recovery,) = _events(trace, "recovery")
    assert recovery["resource"] == "laser(Emil)" and recovery["how"] == "probe"
    assert int(switches[1]["cycle"]) >= 25 + 2 * 20 - 5  # type: ignore[call-overload]
    assert len(_events(trace, "failure")) == 1  # the second failure met no running laser
    stalk = _action(trace, "stalk-robot")
    assert _gap(stalk, 11) <= 3
    assert _gap(stalk, int(switches[1]["cycle"]) + 1) <= 3  # type: ignore[call-overload]


def test_the_helper_lost_and_no_other_helper_stops_safely(tmp_path: Path) -> None:
    code, output, trace = _run(
        [*STEP2, "--impl", str(EXAMPLE_IMPL), "--rate", "0", "--cycles", "30"],
        tmp_path / "T",
        "kill Pippi at cycle 10",
    )
    assert code == 3, output
    (stop,) = _events(trace, "no-configuration")
    assert stop["cause"] == "Pippi failed"
    assert any(
        "(not (eql (quote ?r) (quote ?rh1))) with ?r = Emil, ?rh1 = Emil" in w for w in stop["why"]
    )  # type: ignore[attr-defined]
    assert "F3: cross-door(Emil, Door1)" in stop["stopped"]  # type: ignore[operator]
    assert not [c for c in _action(trace, "cross-door") if int(c["cycle"]) > 10]  # type: ignore[call-overload]
    assert "no admissible configuration (Pippi failed)" in output


def _impl(folder: Path, replaced: str, body: str) -> Path:
    """An implementation file: the example's, with functionality ``replaced`` redone."""
    path = folder / "impl.py"
    path.write_text(
        textwrap.dedent(
            f"""
            from pathlib import Path
            from cfgplan.runtime import ACHIEVED, Implementation, ResourceFailure, functionality
            from cfgplan.runtime import load_module
            _base = load_module(Path({str(EXAMPLE_IMPL)!r}))
            globals().update(
                {{k: v for k, v in vars(_base).items()
                  if isinstance(v, Implementation) and v.name != {replaced!r}}}
            )
            COUNT = [0]
            """
        )
        + textwrap.dedent(body)
    )
    return path


def test_an_implementation_reporting_its_failure_is_switched_out(tmp_path: Path) -> None:
    impl = _impl(
        tmp_path,
        "compass",
        """
        @functionality("compass")
        def compass_(*args):
            COUNT[0] += 1
            if COUNT[0] > 10:
                raise ResourceFailure("magnetic disturbance")
            return 0.3
        """,
    )
    code, output, trace = _run(
        [*STEP2, "--impl", str(impl), "--rate", "0", "--cycles", "20"], tmp_path / "T"
    )
    assert code == 0, output
    failure = _events(trace, "failure")[0]
    assert failure["how"] == "reported" and "magnetic disturbance" in failure["detail"]  # type: ignore[operator]
    assert [s["to_cost"] for s in _events(trace, "switch")] == [47]


@pytest.mark.slow
def test_a_compass_that_falls_silent_is_found_by_staleness(tmp_path: Path) -> None:
    impl = _impl(
        tmp_path,
        "compass",
        """
        @functionality("compass")
        def compass_(*args):
            COUNT[0] += 1
            return None if COUNT[0] > 20 else 0.3
        """,
    )
    code, output, trace = _run(
        [*STEP2, "--impl", str(impl), "--rate", "20", "--cycles", "50"], tmp_path / "T"
    )
    assert code == 0, output
    (failure,) = _events(trace, "failure")
    assert failure["how"] == "stale"
    assert failure["resource"] in ("compass(Emil)", "compass(Pippi)")  # both fell silent
    assert [s["to_cost"] for s in _events(trace, "switch")] == [47]
    assert _gap(_action(trace, "cross-door"), int(failure["cycle"]) + 1) <= 3  # type: ignore[call-overload]


def test_an_operator_update_reconfigures(tmp_path: Path) -> None:
    code, output, trace = _run(
        [*STEP2, "--impl", str(EXAMPLE_IMPL), "--rate", "0", "--cycles", "10"],
        tmp_path / "T",
        "retract (compass Pippi) at cycle 5",
    )
    assert code == 0, output
    (facts,) = _events(trace, "facts")
    assert facts["removed"] == ["(compass Pippi)"] and facts["how"] == "operator"
    assert [s["to_cost"] for s in _events(trace, "switch")] == [47]


def test_an_action_that_accomplishes_its_task_ends_the_run(tmp_path: Path) -> None:
    impl = _impl(
        tmp_path,
        "cross-door",
        """
        @functionality("cross-door")
        def cross_(door, pos, orient):
            COUNT[0] += 1
            return ACHIEVED if COUNT[0] >= 5 else None
        """,
    )
    code, output, trace = _run(
        [*STEP2, "--impl", str(impl), "--rate", "0", "--cycles", "100"], tmp_path / "T"
    )
    assert code == 0, output
    assert [
        e["event"] for e in trace if e["event"] in ("achieved", "switch", "no-configuration")
    ] == ["achieved"]
    assert trace[-1]["event"] == "stop" and trace[-1]["reason"] == "achieved"
    assert int(trace[-1]["cycle"]) < 20  # type: ignore[call-overload]


def test_without_reconfiguration_the_fault_just_happens(tmp_path: Path) -> None:
    code, _, trace = _run(
        [*STEP2, "--impl", str(EXAMPLE_IMPL), "--rate", "0", "--cycles", "10", "--no-reconfigure"],
        tmp_path / "T",
        "fail compass(Emil) at cycle 3",
    )
    assert code == 1  # a functionality failed and nobody handled it
    assert _events(trace, "inject") and not _events(trace, "switch")
    assert all(c["status"] != "ran" for c in _action(trace, "cross-door") if int(c["cycle"]) > 4)  # type: ignore[call-overload]


@pytest.mark.parametrize(
    "bad", ["fail compass(Emil)", "kill compass(Emil) at cycle 2", "fail compass(Emil) at cycle 0"]
)
def test_a_bad_injection_is_a_usage_error(bad: str, tmp_path: Path) -> None:
    result = CliRunner().invoke(app, ["run", *STEP2, "--impl", str(EXAMPLE_IMPL), "--inject", bad])
    assert result.exit_code == 2
    assert "--inject" in result.output and "Traceback" not in result.output


def test_the_fallbacks_thread_ends_with_the_run(tmp_path: Path) -> None:
    """Fallbacks are computed ahead on a thread of their own (5.5); when the
    run is over it ends (a program that runs societies one after another
    kept one idle thread, and its tasks, per run)."""
    before = set(threading.enumerate())
    code, output, _ = _run(
        [*STEP2, "--impl", str(EXAMPLE_IMPL), "--rate", "0", "--cycles", "30"],
        tmp_path / "T",
        "fail compass(Emil) at cycle 20",
    )
    assert code == 0, output
    started = [t for t in threading.enumerate() if t not in before and "fallbacks" in t.name]
    for thread in started:
        thread.join(timeout=20)  # at most the search it is in
    assert not [t for t in started if t.is_alive()]
