"""``cfgplan record``: a real run's trace as an MCAP file, read back with the
``mcap`` package.

The trace is cross-door step 2 (6.2.2) in one process, Emil's compass failing
at cycle 20: a switch from cost 44 to 47. The recording must have one channel
per kind of event (and robot, and global channel), each with the JSON Schema
of its pydantic model, one message per event at the event's time, and be the
same bytes every time.
"""

from __future__ import annotations

import json
import subprocess
import sys
from collections import Counter
from itertools import pairwise
from pathlib import Path
from typing import Any, get_args

import pytest
from mcap.reader import make_reader
from typer.testing import CliRunner

import cfgplan.cli.record  # registers the command
import cfgplan.cli.run  # registers the command
from cfgplan.cli.app import app
from cfgplan.diagnostics import CfgplanError
from cfgplan.record import mcap_export
from cfgplan.runtime import schema as s

ROOT = Path(__file__).resolve().parents[2]
CROSS = ROOT / "domains" / "cross-door"
RUN = [
    "run",
    str(CROSS / "domain.lisp"),
    str(CROSS / "state-6.2.2-step2.lisp"),
    "--impl",
    str(ROOT / "examples" / "cross-door" / "impl.py"),
    "--rate",
    "0",
    "--cycles",
    "100",
    "--inject",
    "fail compass(Emil) at cycle 20",
]


@pytest.fixture(scope="module")
def trace(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The trace of the run, written by ``cfgplan run --trace``."""
    path = tmp_path_factory.mktemp("run") / "trace.jsonl"
    result = CliRunner().invoke(app, [*RUN, "--trace", str(path)])
    assert result.exit_code == 0, result.output
    return path


def _events(path: Path) -> list[dict[str, Any]]:
    return [json.loads(line) for line in path.read_text(encoding="utf-8").splitlines()]


def _record(trace: Path, output: Path, *extra: str) -> None:
    result = CliRunner().invoke(app, ["record", str(trace), "-o", str(output), *extra])
    assert result.exit_code == 0, result.output
    assert f"wrote {output}: " in result.stderr


def _cfgplan(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "cfgplan", *args],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=120,
    )


def _expected_topic(e: dict[str, Any]) -> str:
    """The topic of an event, said again here independently of TOPICS for the
    kinds this run has."""
    robot, kind = e["robot"], e["event"]
    if kind == "call":
        return f"/cfgplan/{robot}/calls"
    if kind in ("send", "receive"):
        way = "sent" if kind == "send" else "received"
        return f"/cfgplan/{robot}/channels/{e['channel'].replace(' ', '_')}/{way}"
    if kind == "install":
        return f"/cfgplan/{robot}/installs"
    plural = {"start": "starts", "stop": "stops", "inject": "injections"}
    return "/cfgplan/" + str(plural.get(kind, kind + ("es" if kind.endswith("h") else "s")))


@pytest.fixture(scope="module")
def recorded(trace: Path) -> Path:
    output = trace.with_name("run.mcap")
    _record(trace, output)
    return output


def test_every_kind_of_event_has_a_topic() -> None:
    """TOPICS names every model a trace line can be, and no two the same topic."""
    models = set(get_args(get_args(s.TraceEvent)[0]))
    assert set(mcap_export.TOPICS) == models
    assert len(set(mcap_export.TOPICS.values())) == len(models)


@pytest.mark.slow
def test_channels_schemas_and_counts(trace: Path, recorded: Path) -> None:
    """One channel per kind of event (per robot, per global channel and way),
    JSON messages, each with the JSON Schema of its model; as many messages on
    each as the trace has events of that kind there."""
    events = _events(trace)
    kinds = {e["event"] for e in events}
    assert kinds == {"start", "call", "send", "receive", "inject", "failure", "switch"} | {
        "install",
        "stop",
    }
    expected = Counter(_expected_topic(e) for e in events)
    with recorded.open("rb") as stream:
        reader = make_reader(stream)
        summary = reader.get_summary()
        assert summary is not None
        channels = {c.topic: c for c in summary.channels.values()}
        assert set(channels) == set(expected)
        assert [c.topic for c in sorted(summary.channels.values(), key=lambda c: c.id)] == sorted(
            expected
        )  # registered in a fixed order
        for must in (
            "/cfgplan/switches",
            "/cfgplan/failures",
            "/cfgplan/Emil/calls",
            "/cfgplan/Pippi/channels/F7->F3_(pos_Emil_Door1)/sent",
            "/cfgplan/Emil/channels/F7->F3_(pos_Emil_Door1)/received",
        ):
            assert must in channels, must
        models = {mcap_export.schema_name(m): m for m in mcap_export.TOPICS}
        kinds_of = {m: set(get_args(m.model_fields["event"].annotation)) for m in models.values()}
        counted: Counter[str] = Counter()
        for schema, channel, message in reader.iter_messages(log_time_order=False):
            assert schema is not None
            assert channel.message_encoding == "json"
            assert schema.encoding == "jsonschema"
            model = models[schema.name]
            document = json.loads(schema.data)
            assert document == model.model_json_schema() and document["type"] == "object"
            event = model.model_validate_json(message.data)  # the schema's model reads it
            assert event.event in kinds_of[model]  # type: ignore[attr-defined]
            counted[channel.topic] += 1
        assert counted == expected
        assert summary.statistics is not None
        assert summary.statistics.message_count == len(events)
    assert channels["/cfgplan/Emil/calls"].metadata == {"robot": "Emil"}
    assert channels["/cfgplan/Pippi/channels/F7->F3_(pos_Emil_Door1)/sent"].metadata == {
        "robot": "Pippi",
        "channel": "F7->F3 (pos Emil Door1)",
    }


def test_the_switch_and_the_times(trace: Path, recorded: Path) -> None:
    """The switch message says 44 -> 47 (fallback, compass(Emil) failed); every
    message is at its event's ``t`` in nanoseconds, in the trace's order, and the
    log times never go back; a received value is published at the sender's time."""
    events = _events(trace)
    with recorded.open("rb") as stream:
        reader = make_reader(stream)
        messages = list(reader.iter_messages(log_time_order=False))
    ((_, _, switch),) = [m for m in messages if m[1].topic == "/cfgplan/switches"]
    body = json.loads(switch.data)
    assert (body["from_cost"], body["to_cost"]) == (44, 47)
    assert body["source"] == "fallback" and body["cause"] == "compass(Emil) failed"
    assert body["robot"] == "Emil" and body["cycle"] == 20
    assert "F10: compass(Emil)" in body["stopped"]["functionalities"]
    times = [m.log_time for _, _, m in messages]
    assert times == [mcap_export.nanoseconds(e["t"]) for e in events]
    assert all(a <= b for a, b in pairwise(times))
    assert times[0] < times[-1]
    assert abs(switch.log_time - round(body["t"] * 1e9)) < 1000
    received = [m for _, c, m in messages if c.topic.endswith("/received")]
    assert received and all(m.publish_time <= m.log_time for m in received)
    assert any(m.publish_time < m.log_time for m in received)


def test_the_same_trace_gives_the_same_bytes(trace: Path, recorded: Path, tmp_path: Path) -> None:
    """Converted again, from a copy elsewhere, the file is byte for byte the same:
    no clock, no path in it."""
    copy = tmp_path / "elsewhere.jsonl"
    copy.write_bytes(trace.read_bytes())
    again = tmp_path / "again.mcap"
    _record(copy, again)
    assert again.read_bytes() == recorded.read_bytes()
    data, _ = mcap_export.convert([trace])
    assert data == recorded.read_bytes()


def test_a_rotated_trace_is_read_whole(trace: Path, recorded: Path, tmp_path: Path) -> None:
    """A trace that rotated (FILE.1, then FILE) records as the whole trace would."""
    lines = trace.read_bytes().splitlines(keepends=True)
    half = len(lines) // 2
    split = tmp_path / "trace.jsonl"
    split.with_name("trace.jsonl.1").write_bytes(b"".join(lines[:half]))
    split.write_bytes(b"".join(lines[half:]))
    output = tmp_path / "rotated.mcap"
    result = CliRunner().invoke(app, ["record", str(split), "-o", str(output)])
    assert result.exit_code == 0, result.output
    assert f"from {split}.1 then {split}" in result.stderr
    assert output.read_bytes() == recorded.read_bytes()


@pytest.mark.slow
def test_a_bad_line_is_named_by_file_and_line(trace: Path, tmp_path: Path) -> None:
    """A line that is not JSON, or JSON but not an event, is refused with its
    file:line (exit 1, no traceback) and nothing is written."""
    head = trace.read_text(encoding="utf-8").splitlines()[:3]
    cases = {
        "broken.jsonl": ('{"event": "call", "robot"', "broken.jsonl:4:26: error: not JSON: "),
        "stranger.jsonl": (
            '{"event": "call", "robot": "Emil", "t": 1.5, "cycle": 3}',
            "stranger.jsonl:4:1: error: not a trace event (call): label: Field required",
        ),
        "list.jsonl": ("[1, 2]", "list.jsonl:4:1: error: not a trace event: a JSON object"),
    }
    for name, (line, message) in cases.items():
        path = tmp_path / name
        path.write_text("\n".join([*head, line]) + "\n", encoding="utf-8")
        output = tmp_path / f"{name}.mcap"
        out = _cfgplan("record", str(path), "-o", str(output))
        assert out.returncode == 1, out.stderr
        assert message in out.stderr, out.stderr
        assert "Traceback" not in out.stderr
        assert not output.exists()
    out = _cfgplan("record", str(tmp_path / "missing.jsonl"), "-o", str(tmp_path / "m.mcap"))
    assert out.returncode == 1 and "no such trace file" in out.stderr, out.stderr


@pytest.mark.slow
def test_an_existing_file_is_kept_without_force(trace: Path, tmp_path: Path) -> None:
    """``-o`` names a file there already: exit 1, untouched; ``--force`` replaces it,
    unless it is the trace itself."""
    output = tmp_path / "run.mcap"
    output.write_bytes(b"keep me")
    out = _cfgplan("record", str(trace), "-o", str(output))
    assert out.returncode == 1
    assert "exists; pass --force to overwrite it" in out.stderr
    assert output.read_bytes() == b"keep me"
    out = _cfgplan("record", str(trace), "-o", str(output), "--force")
    assert out.returncode == 0, out.stderr
    assert output.read_bytes().startswith(b"\x89MCAP0\r\n")
    copy = tmp_path / "copy.jsonl"
    copy.write_bytes(trace.read_bytes())
    out = _cfgplan("record", str(copy), "-o", str(copy), "--force")  # not even with --force
    assert out.returncode == 1 and "is the trace itself" in out.stderr, out.stderr
    assert copy.read_bytes() == trace.read_bytes()


def test_without_mcap_the_command_says_what_to_install(monkeypatch: pytest.MonkeyPatch) -> None:
    """With the ``mcap`` package missing, a clear error naming the extra."""
    for name in [m for m in sys.modules if m == "mcap" or m.startswith("mcap.")]:
        monkeypatch.setitem(sys.modules, name, None)
    monkeypatch.setitem(sys.modules, "mcap", None)
    monkeypatch.delitem(sys.modules, "cfgplan.record.mcap_export")
    monkeypatch.delattr("cfgplan.record.mcap_export")
    with pytest.raises(CfgplanError) as caught:
        cfgplan.cli.record.load_exporter()
    (diagnostic,) = caught.value.diagnostics
    assert "needs the mcap package" in diagnostic.message
    assert diagnostic.hint is not None and "pip install 'cfgplan[record]'" in diagnostic.hint


def test_the_core_commands_do_not_load_mcap() -> None:
    """Registering every command (as ``cfgplan --help`` does) imports no mcap."""
    code = "import sys, cfgplan.cli.commands; print('mcap' in sys.modules)"
    out = subprocess.run(
        [sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=60
    )
    assert out.stdout.strip() == "False", out.stderr
