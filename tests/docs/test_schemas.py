"""The schemas of the reference pages hold for the real outputs.

``cfgplan plan --format json|jsonl`` on every bundled state, with ``--fallbacks``
and with nothing admissible, is validated against
:mod:`cfgplan.configuration.schema`, and the trace of a real run with faults
injected, a switch and a robot lost against :mod:`cfgplan.runtime.schema`.
Every model forbids keys it does not name, so a key added to an output (or
one the models name but the output no longer has, when required) fails here
until the models, and with them the documentation, say so.
"""

from __future__ import annotations

import json
import socket
import subprocess
import sys
from pathlib import Path

import pytest
from pydantic import BaseModel, ValidationError
from typer.testing import CliRunner

from cfgplan.configuration.schema import (
    ConfigurationEntry,
    PlanDocument,
    PlanSummary,
    SequenceDocument,
    SequenceEntry,
)
from cfgplan.runtime.schema import TRACE_EVENT

ROOT = Path(__file__).resolve().parents[2]
STATES = sorted((ROOT / "domains").glob("*/state-*.lisp"))
DOMAINS = {  # the domain of a state, when not domain.lisp beside it
    "state-4.6-media.lisp": "domain-bandwidth.lisp",
    "state-6.2.2-sequence.lisp": "domain-steps.lisp",
}


def _domain(state: Path) -> Path:
    return state.parent / DOMAINS.get(state.name, "domain.lisp")


def _plan(*args: str) -> tuple[int, str]:
    """``cfgplan plan ARGS`` in this process: the exit code and stdout."""
    import cfgplan.cli.commands  # noqa: F401  (loads every command module)
    from cfgplan.cli.app import app

    out = CliRunner().invoke(app, ["plan", *args], catch_exceptions=False)
    return out.exit_code, out.stdout


def _line_model(line: dict[str, object]) -> type[BaseModel]:
    if "steps" in line:
        return SequenceEntry
    return PlanSummary if "count" in line else ConfigurationEntry


@pytest.mark.parametrize("state", STATES, ids=[f"{s.parent.name}/{s.stem}" for s in STATES])
def test_plan_outputs_of_every_bundled_state_match_the_schema(state: Path) -> None:
    files = (str(_domain(state)), str(state))
    code, out = _plan(*files, "--format", "json")
    assert code in (0, 3), out
    document = json.loads(out)
    model = SequenceDocument if "sequences" in document else PlanDocument
    model.model_validate_json(out)
    if code == 3:
        assert document["explanation"]["dead_ends"], "nothing admissible says why"
    code, out = _plan(*files, "--format", "jsonl")
    assert code in (0, 3), out
    lines = out.splitlines()
    assert lines
    for line in lines:
        _line_model(json.loads(line)).model_validate_json(line)
    if model is PlanDocument:
        assert "count" in json.loads(lines[-1]), "the last line of jsonl is the summary"


def test_fallbacks_match_the_schema() -> None:
    cross = ("domains/cross-door/domain.lisp", "domains/cross-door/state-6.2.2-step1.lisp")
    code, out = _plan(*(str(ROOT / f) for f in cross), "--format", "json", "--fallbacks")
    assert code == 0, out
    assert PlanDocument.model_validate_json(out).fallbacks


def test_the_models_refuse_what_the_outputs_do_not_have() -> None:
    """The check above can fail: an unknown key, a missing one, a wrong type."""
    folder = ROOT / "domains/cross-door"
    files = [str(folder / f) for f in ("domain.lisp", "state-6.2.2-step1.lisp")]
    _, out = _plan(*files, "--format", "json", "-k", "1")
    good = json.loads(out)
    PlanDocument.model_validate(good)
    unknown = {**good, "extra": 1}
    missing = {k: v for k, v in good.items() if k != "stats"}
    config = {**good["configurations"][0], "cost": "44"}
    for bad in (unknown, missing, {**good, "configurations": [config]}):
        with pytest.raises(ValidationError):
            PlanDocument.model_validate_json(json.dumps(bad))


FAULTS = (
    "fail compass(Emil) at cycle 5",
    "recover compass(Emil) at cycle 12",
    "retract (compass Pippi) at cycle 20",
    "assert (compass Pippi) at cycle 25",
    "kill Pippi at cycle 30",
)


@pytest.mark.slow
def test_a_run_trace_matches_the_schema(tmp_path: Path) -> None:
    """Cross-door step 2 (6.2.2) in one process: Emil's compass fails (a switch to
    47), recovers, the operator changes the state, Pippi is killed (nothing is
    admissible then: a safe stop, exit 3)."""
    trace = tmp_path / "trace.jsonl"
    command = [
        sys.executable,
        "-m",
        "cfgplan",
        "run",
        "domains/cross-door/domain.lisp",
        "domains/cross-door/state-6.2.2-step2.lisp",
        "--impl",
        "examples/cross-door/impl.py",
        "--cycles",
        "40",
        "--rate",
        "50",
        "--hold",
        "0.05",
        "--trace",
        str(trace),
    ]
    for fault in FAULTS:
        command += ["--inject", fault]
    out = subprocess.run(command, cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert out.returncode in (0, 3), out.stderr
    kinds = set()
    for line in trace.read_text(encoding="utf-8").splitlines():
        kinds.add(TRACE_EVENT.validate_json(line).event)
    expected = {"start", "call", "send", "receive", "inject", "failure", "switch", "install"}
    expected |= {"facts", "robot-lost", "stop"}
    assert expected <= kinds, sorted(expected - kinds)
    stop = {"event": "stop", "robot": "Emil", "t": 1.0, "cycle": 1, "reason": "cycles"}
    TRACE_EVENT.validate_json(json.dumps(stop))
    with pytest.raises(ValidationError):
        TRACE_EVENT.validate_json(json.dumps({**stop, "extra": 1}))


@pytest.mark.slow
def test_a_simulation_trace_matches_the_schema(tmp_path: Path) -> None:
    """``cfgplan simulate cross-door`` (6.2.2, both steps, Emil's compass
    disturbed): its trace.jsonl has the schema of ``--trace``, in simulated time."""
    command = [sys.executable, "-m", "cfgplan", "simulate", "cross-door", "--out", str(tmp_path)]
    out = subprocess.run(command, cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    kinds = set()
    for line in (tmp_path / "trace.jsonl").read_text(encoding="utf-8").splitlines():
        kinds.add(TRACE_EVENT.validate_json(line).event)
    assert {"failure", "recovery", "switch", "achieved", "install"} <= kinds, sorted(kinds)


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port: int = s.getsockname()[1]
        return port


@pytest.mark.slow
def test_traces_of_two_robot_processes_match_the_schema(tmp_path: Path) -> None:
    """Emil and Pippi (6.2.2 step 1) as two emitted programs over Zenoh on
    loopback: presence, staleness and messages between processes."""
    files = ("domains/cross-door/domain.lisp", "domains/cross-door/state-6.2.2-step1.lisp")
    out = tmp_path / "out"
    emit = [sys.executable, "-m", "cfgplan", "emit", *files, "--lang", "python", "-o", str(out)]
    subprocess.run(emit, cwd=ROOT, check=True, capture_output=True, timeout=120)
    endpoint = f"tcp/127.0.0.1:{_free_port()}"
    common = ["--impl", "examples/cross-door/impl.py", "--society", f"schema-{tmp_path.name}"]
    emil_command = [sys.executable, str(out / "emil.py"), *common, "--listen", endpoint]
    emil_command += ["--cycles", "20", "--trace", str(tmp_path / "emil.jsonl")]
    emil = subprocess.Popen(
        emil_command,
        cwd=ROOT,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        pippi = [sys.executable, str(out / "pippi.py"), *common, "--connect", endpoint]
        pippi += ["--cycles", "40", "--trace", str(tmp_path / "pippi.jsonl")]
        subprocess.run(pippi, cwd=ROOT, capture_output=True, timeout=120, check=True)
        assert emil.wait(timeout=60) == 0
    finally:
        if emil.poll() is None:
            emil.kill()
            emil.wait(timeout=10)
    kinds = set()
    for trace in ("emil.jsonl", "pippi.jsonl"):
        for line in (tmp_path / trace).read_text(encoding="utf-8").splitlines():
            kinds.add(TRACE_EVENT.validate_json(line).event)
    assert {"robot-seen", "robot-lost", "send", "receive", "stale"} <= kinds, sorted(kinds)
