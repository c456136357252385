"""``--record FILE.mcap`` on ``cfgplan run`` and ``cfgplan simulate``: a run
written to MCAP as it happens, read back with the ``mcap`` package.

The run is cross-door step 2 (6.2.2), Emil's compass failing: a switch from
cost 44 to 47. The recording must hold what ``cfgplan record`` makes of the
same run's trace (the same topics, schemas and message bytes), be written
while the run goes (a reader sees the switch before the run ends; a run
killed by SIGKILL keeps it), and be capped like a trace.
"""

from __future__ import annotations

import io
import json
import os
import signal
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
from mcap.reader import make_reader
from typer.testing import CliRunner

import cfgplan.cli.run  # registers the command
import cfgplan.cli.simulate  # noqa: F401  (loads the command module)
from cfgplan.cli.app import app
from cfgplan.record import channels, mcap_export
from cfgplan.record.live import open_recording, salvage
from cfgplan.record.policy import Policy
from cfgplan.runtime import schema as s
from cfgplan.runtime.errors import RunError
from tests.runtime.netutil import endpoint, free_port, hermetic_config, processes, wait_for

ROOT = Path(__file__).resolve().parents[2]
CROSS = ROOT / "domains" / "cross-door"


def _run_args(cycles: int, rate: float, at: int | None) -> list[str]:
    inject = [] if at is None else ["--inject", f"fail compass(Emil) at cycle {at}"]
    return [
        "run",
        str(CROSS / "domain.lisp"),
        str(CROSS / "state-6.2.2-step2.lisp"),
        "--impl",
        str(ROOT / "examples" / "cross-door" / "impl.py"),
        "--rate",
        str(rate),
        "--cycles",
        str(cycles),
        *inject,
    ]


def _read(path: Path) -> tuple[Any, list[tuple[Any, Any, Any]]]:
    """The summary and the messages (in the order written) of a whole file."""
    with path.open("rb") as stream:
        reader = make_reader(stream)
        summary = reader.get_summary()
        messages = list(reader.iter_messages(log_time_order=False))
    return summary, messages


def _check_schemas(messages: list[tuple[Any, Any, Any]]) -> None:
    """Every channel is JSON with the JSON Schema of its kind's model, which reads it."""
    models = {channels.schema_name(m): m for m in channels.TOPICS}
    for schema, channel, message in messages:
        assert schema is not None and schema.encoding == "jsonschema"
        assert channel.message_encoding == "json"
        model = models[schema.name]
        assert json.loads(schema.data) == model.model_json_schema(by_alias=True)
        model.model_validate_json(message.data)


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """A run with both --trace and --record (every robot in this process)."""
    folder = tmp_path_factory.mktemp("run")
    trace, record = folder / "trace.jsonl", folder / "run.mcap"
    args = [*_run_args(100, 0, 20), "--trace", str(trace), "--record", str(record)]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    return trace, record


@pytest.mark.slow
def test_the_recording_holds_the_switch_with_its_schema(recorded: tuple[Path, Path]) -> None:
    """The switch is on /cfgplan/switches, schema cfgplan.trace.SwitchEvent, 44 -> 47;
    every channel has its kind's JSON Schema; the file's metadata counts the events."""
    _, record = recorded
    summary, messages = _read(record)
    switches = [(sc, m) for sc, c, m in messages if c.topic == "/cfgplan/switches"]
    ((schema, switch),) = switches
    assert schema.name == "cfgplan.trace.SwitchEvent"
    assert json.loads(schema.data) == s.SwitchEvent.model_json_schema(by_alias=True)
    body = json.loads(switch.data)
    assert (body["from_cost"], body["to_cost"], body["cycle"]) == (44, 47, 20)
    assert body["cause"] == "compass(Emil) failed"
    _check_schemas(messages)
    assert summary.statistics.chunk_count >= 2  # written in pieces, not at the end
    (meta,) = [m for m in make_reader(record.open("rb")).iter_metadata()]
    assert meta.name == "cfgplan" and meta.metadata["events"] == str(len(messages))


def test_the_recording_is_what_cfgplan_record_makes_of_the_trace(
    recorded: tuple[Path, Path],
) -> None:
    """Same topics, channel metadata, schemas, and message bytes and times, in
    the same order, as the trace of the same run converted afterwards."""
    trace, record = recorded
    batch, _ = mcap_export.convert([trace])
    _, live = _read(record)
    reader = make_reader(io.BytesIO(batch))
    converted = list(reader.iter_messages(log_time_order=False))
    assert len(live) == len(converted) == len(trace.read_text("utf-8").splitlines())

    def key(m: tuple[Any, Any, Any]) -> tuple[object, ...]:
        schema, channel, message = m
        return (
            channel.topic,
            channel.metadata,
            schema.name,
            schema.data,
            message.data,
            message.log_time,
            message.publish_time,
        )

    assert [key(m) for m in live] == [key(m) for m in converted]


@pytest.mark.slow
def test_written_while_the_run_goes_and_kept_when_killed(tmp_path: Path) -> None:
    """A run at 20 cycles a second: the file grows and the switch (cycle 40)
    can be read from it while the run goes on; killed by SIGKILL, the file
    keeps every chunk written, the switch included (no footer: read from its
    start)."""
    record = tmp_path / "run.mcap"
    args = ["-m", "cfgplan", *_run_args(100000, 20, 40), "--record", str(record)]

    def switch() -> dict[str, Any] | None:
        if not record.exists():
            return None
        with record.open("rb") as stream:
            data = stream.read()
        for _, channel, message in salvage(io.BytesIO(data)):
            if channel.topic == "/cfgplan/switches":
                return {"switch": json.loads(message.data), "size": len(data)}
        return None

    with processes() as running:
        process = running.start(args, tmp_path / "run.log")
        sizes = []
        wait_for("the recording", lambda: {"ok": 1} if record.exists() else None, 30)
        found = wait_for("the switch in the recording", switch, 60, poll=0.1)
        sizes.append(record.stat().st_size)
        assert process.poll() is None, "the run ended before its recording was read"
        switched = found["switch"]
        assert isinstance(switched, dict) and switched["to_cost"] == 47
        wait_for(
            "the recording to grow",
            lambda: {"ok": 1} if record.stat().st_size > sizes[0] else None,
            10,
            poll=0.1,
        )
        os.kill(process.pid, signal.SIGKILL)
        process.wait(timeout=30)
    data = record.read_bytes()
    assert not data.endswith(b"\x89MCAP0\r\n")  # killed: no footer
    topics = [c.topic for _, c, _ in salvage(io.BytesIO(data))]
    assert "/cfgplan/switches" in topics and len(topics) > 200


@pytest.mark.slow
def test_robots_over_zenoh_record_their_own_events(tmp_path: Path) -> None:
    """``--robot NAME`` over Zenoh (loopback, scouting off): each robot's process
    records its own events, the same as its trace converted; Emil's has the
    switch, Pippi's the configuration it installs at the switch."""
    config = str(hermetic_config(tmp_path))
    port = free_port()
    common = ["--zenoh-config", config, "--society", "record-test", "--lease", "1"]
    network = {
        "Emil": [*_run_args(160, 20, 60), "--listen", endpoint(port), *common],
        "Pippi": [
            *_run_args(100000, 20, None),
            *("--listen", endpoint(free_port()), "--connect", endpoint(port)),
            *common,
        ],
    }
    with processes() as running:
        started = {}
        for name in ("Emil", "Pippi"):
            args = ["-m", "cfgplan", *network[name], "--robot", name]
            args += ["--trace", str(tmp_path / f"{name}.jsonl")]
            args += ["--record", str(tmp_path / f"{name}.mcap")]
            started[name] = running.start(args, tmp_path / f"{name}.log")
        assert started["Emil"].wait(90) == 0
        started["Pippi"].send_signal(signal.SIGTERM)  # a clean stop: the file is finished
        started["Pippi"].wait(30)
    for name, topic in (("Emil", "/cfgplan/switches"), ("Pippi", "/cfgplan/Pippi/installs")):
        trace, record = tmp_path / f"{name}.jsonl", tmp_path / f"{name}.mcap"
        _, messages = _read(record)
        _check_schemas(messages)
        assert [m.data for _, _, m in messages] == trace.read_bytes().splitlines()
        bodies = [json.loads(m.data) for _, c, m in messages if c.topic == topic]
        assert any(b.get("id") == 1 for b in bodies), (name, bodies)
    switch = next(
        json.loads(m.data)
        for _, c, m in _read(tmp_path / "Emil.mcap")[1]
        if c.topic == "/cfgplan/switches"
    )
    assert (switch["from_cost"], switch["to_cost"]) == (44, 47)


@pytest.mark.slow  # the simulation draws its pictures too: seconds
def test_a_simulation_records_too(tmp_path: Path) -> None:
    """``cfgplan simulate cross-door --record``: the switch, every schema, the
    trace.jsonl lines as the messages, in simulated time, in several chunks."""
    record, out = tmp_path / "sim.mcap", tmp_path / "out"
    result = CliRunner().invoke(
        app, ["simulate", "cross-door", "--out", str(out), "--quiet", "--record", str(record)]
    )
    assert result.exit_code == 0, result.output
    summary, messages = _read(record)
    _check_schemas(messages)
    lines = (out / "trace.jsonl").read_bytes().splitlines()
    assert [m.data for _, _, m in messages] == lines
    switches = [json.loads(m.data) for _, c, m in messages if c.topic == "/cfgplan/switches"]
    assert switches and all(sw["t"] < 100 for sw in switches)  # simulated seconds
    assert summary.statistics.chunk_count >= 2


def test_a_recording_is_capped_like_a_trace(recorded: tuple[Path, Path], tmp_path: Path) -> None:
    """Past the cap, FILE is finished and becomes FILE.1 and a new FILE begins:
    both whole MCAP files under the cap, the newest events in FILE."""
    trace, _ = recorded
    path = tmp_path / "capped.mcap"
    cap = 60_000
    recorder = open_recording(path, policy=Policy(max_bytes=cap, flush_every=0.05))
    lines = trace.read_bytes().splitlines()
    for line in lines:
        recorder.add(json.loads(line), line)
    recorder.close()
    assert recorder.failed is None and recorder.rotations >= 1
    rotated = path.with_name("capped.mcap.1")
    for f in (path, rotated):
        assert f.stat().st_size <= cap, f
    _, newest = _read(path)
    _, before = _read(rotated)
    assert [m.data for _, _, m in before + newest] == lines[-(len(before) + len(newest)) :]


def test_an_existing_file_is_kept_without_force(tmp_path: Path) -> None:
    """--record names a file there already: exit 1, a clear message, untouched."""
    record = tmp_path / "run.mcap"
    record.write_bytes(b"keep me")
    out = subprocess.run(
        [sys.executable, "-m", "cfgplan", *_run_args(5, 0, 2), "--record", str(record)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert out.returncode == 1, out.stderr
    assert "exists; pass --force to overwrite it" in out.stderr
    assert "Traceback" not in out.stderr
    assert record.read_bytes() == b"keep me"


def test_without_mcap_record_says_what_to_install(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    """With the ``mcap`` package missing, --record is a clear error naming the extra."""
    from cfgplan.record.launch import start_recording

    monkeypatch.setitem(sys.modules, "mcap", None)
    monkeypatch.setitem(sys.modules, "mcap.writer", None)
    monkeypatch.delitem(sys.modules, "cfgplan.record.live", raising=False)
    monkeypatch.delitem(sys.modules, "cfgplan.record.mcap_export", raising=False)
    with pytest.raises(RunError) as caught:
        start_recording(tmp_path / "x.mcap", False)
    assert "--record needs the mcap package" in str(caught.value)
    assert caught.value.hint == "pip install 'cfgplan[record]'"
    assert not (tmp_path / "x.mcap").exists()


def test_a_run_without_the_options_imports_neither() -> None:
    """``cfgplan run`` without --record and --foxglove loads neither mcap nor foxglove."""
    code = (
        "import sys\n"
        "from cfgplan.cli.app import main\n"
        f"sys.argv = ['cfgplan', *{_run_args(5, 0, 2)!r}]\n"
        "try:\n    main()\nexcept SystemExit:\n    pass\n"
        "print('mcap' in sys.modules, 'foxglove' in sys.modules, file=sys.stderr)"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=120
    )
    assert out.stderr.strip().splitlines()[-1] == "False False", out.stderr
