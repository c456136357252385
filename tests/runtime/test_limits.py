"""Everything bounded: a value over the size limit is refused on
send and dropped unread on receipt (5.2.2: a global channel copies data to
another robot; the limit keeps one robot's output from swamping the others)."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import pytest

from cfgplan.runtime import Implementation, Part, Registry, Society, build
from cfgplan.runtime.errors import RunError
from cfgplan.runtime.events import Call, Lifecycle, Transfer
from cfgplan.runtime.part import CallSpec, ChannelSpec
from cfgplan.runtime.tracefile import ELIDE, open_trace
from cfgplan.runtime.transport import InProcessTransport
from cfgplan.runtime.values import MAX_VALUE_BYTES, elide, envelope
from cfgplan.sim.record import ELIDE as SIM_ELIDE

BIG = "x" * 24_000_000  # 24 MB: the value
MIB = 1_048_576


def _pair(value: object) -> tuple[Society, InProcessTransport]:
    """Emil's camera writes ``value`` to Pippi over a global channel; Pippi's
    viewer reads it."""
    image = ("image", "Emil")
    emil = Part(
        "Emil",
        (ChannelSpec("global", "F1", "F2", image, "Pippi"),),
        (CallSpec("F1", "camera", (), (), ((0,),)),),
    )
    pippi = Part(
        "Pippi",
        (ChannelSpec("global", "F1", "F2", image, "Emil"),),
        (CallSpec("F2", "viewer", (), ((0,),), ()),),
    )
    registry = Registry(
        [
            Implementation("camera", lambda: value),
            Implementation("viewer", lambda image: None),
        ]
    )
    transport = InProcessTransport()
    robots = [build(p, registry, transport) for p in (emil, pippi)]
    return Society(robots, transport), transport


def test_the_default_limit_is_one_mebibyte() -> None:
    assert MAX_VALUE_BYTES == 1 << 20 == MIB


def test_an_output_over_the_limit_is_the_calls_error_and_is_not_sent() -> None:
    running, transport = _pair(BIG)
    running.run(cycles=2)
    camera = [e for e in running.calls if e.name == "camera"]
    assert [e.status for e in camera] == ["error", "error"]
    assert camera[0].error == (
        "output image(Emil) goes to another robot, but its JSON is 24,000,002 bytes, "
        "over the limit of 1,048,576 bytes (--max-value-bytes); not sent"
    )
    assert not [e for e in running.events if isinstance(e, Transfer)]
    assert transport.undelivered == 0
    viewer = [e for e in running.calls if e.name == "viewer"]
    assert viewer and all(e.status == "waiting" for e in viewer)


def test_the_limit_is_settable_and_zero_lifts_it() -> None:
    running, _ = _pair("x" * 200)
    running.run(cycles=1, max_value_bytes=100)
    (camera,) = [e for e in running.calls if e.name == "camera"]
    assert camera.status == "error" and "202 bytes, over the limit of 100 bytes" in camera.error
    running, _ = _pair("x" * 2 * MIB)
    running.run(cycles=2, max_value_bytes=0)
    assert {e.status for e in running.calls if e.name == "camera"} == {"ran"}
    assert any(e.name == "viewer" and e.status == "ran" for e in running.calls)


@pytest.mark.parametrize("well_formed", [True, False])
def test_a_message_over_the_limit_is_dropped_unread(well_formed: bool) -> None:
    """Received from the network: dropped before it is parsed (a 24 MB
    message that is not even JSON says so by its size, not by a parse error),
    recorded with its size; the channel stays as it was."""
    running, transport = _pair(None)
    running.run(cycles=1)
    pippi = running.robot("Pippi")
    assert pippi is not None
    channel = pippi.channels[0]
    payload = envelope("Emil", 1, 0.0, None, json.dumps(BIG)) if well_formed else b"{" * 24_000_000
    transport.send(channel.key, "Pippi", payload)
    transport.poll()
    (dropped,) = [e for e in pippi.events if isinstance(e, Lifecycle) and e.what == "error"]
    info = dict(dropped.info)
    assert info["bytes"] == len(payload) and info["limit"] == MIB
    assert info["channel"] == "F1->F2 (image Emil)"
    assert f"a message of {len(payload):,} bytes, over the limit of 1,048,576 bytes" in str(
        info["message"]
    )
    assert "dropped unread" in str(info["message"])
    assert not channel.fresh and channel.peek() is None
    assert not [e for e in pippi.events if isinstance(e, Transfer)]
    assert not [e for e in pippi.events if isinstance(e, Call) and e.status == "ran" and e.inputs]


def test_a_trace_records_large_values_by_size_and_digest(tmp_path: Path) -> None:
    """24 MB values grew the trace by 96 MB in 12 s. A value over
    :data:`ELIDE` characters is recorded by its type, size and the SHA-256 of
    its JSON, the same on the sending and the receiving robot."""
    value = "x" * 2 * MIB
    running, _ = _pair(value)
    path = tmp_path / "run.jsonl"
    trace = open_trace(path)
    running.subscribe(trace)
    running.run(cycles=3, max_value_bytes=0)
    trace.close()
    assert path.stat().st_size < 20_000
    lines = [json.loads(x) for x in path.read_text(encoding="utf-8").splitlines()]
    text = json.dumps(value, separators=(",", ":")).encode()
    note = {
        "$elided": "str",
        "$bytes": len(text),
        "$sha256": hashlib.sha256(text).hexdigest()[:16],
    }
    sent = [e["value"] for e in lines if e["event"] in ("send", "receive")]
    assert len(sent) >= 4 and all(v == note for v in sent)
    outputs = [e["outputs"] for e in lines if e["event"] == "call" and e.get("outputs")]
    assert outputs and all(o[0]["value"] == note for o in outputs)
    viewer = [e for e in lines if e["event"] == "call" and e["functionality"] == "viewer"]
    assert any(e.get("inputs") and e["inputs"][0]["value"] == note for e in viewer)


def test_short_values_stay_whole_and_the_rule_is_the_simulators_too() -> None:
    assert elide([1.5, "a", None], ELIDE) == [1.5, "a", None]
    assert elide("é" * 600, ELIDE) == "é" * 600  # 3,602 characters of JSON: whole
    assert elide("é" * 700, ELIDE)["$bytes"] == 4202  # type: ignore[index]
    assert elide(BIG, 0) is BIG  # 0: no limit
    assert elide(object(), 10)["$elided"] == "object"  # type: ignore[index]
    scan = {"ranges": [float(i) for i in range(200)]}
    noted = elide(scan, SIM_ELIDE)
    assert isinstance(noted, dict) and set(noted) == {"$elided", "$bytes", "$sha256"}


def test_a_trace_file_rotates_once_past_its_cap(tmp_path: Path) -> None:
    """Past ``max_bytes`` FILE becomes FILE.1 and a new FILE begins: at most
    twice the cap on disk, the newest events kept."""
    path = tmp_path / "run.jsonl"
    trace = open_trace(path, max_bytes=2_000)
    for k in range(200):
        trace(Lifecycle(robot="Emil", t=float(k), what="error", info=(("message", f"m{k}"),)))
    trace.close()
    old = tmp_path / "run.jsonl.1"
    assert trace.rotations > 2 and sorted(p.name for p in tmp_path.iterdir()) == [
        "run.jsonl",
        "run.jsonl.1",
    ]
    assert path.stat().st_size <= 2_000 and old.stat().st_size <= 2_000
    newest = [json.loads(x)["message"] for x in path.read_text().splitlines()]
    before = [json.loads(x)["message"] for x in old.read_text().splitlines()]
    assert newest[-1] == "m199"
    assert int(before[-1][1:]) + 1 == int(newest[0][1:])  # FILE.1 ends where FILE begins


def test_a_rotated_file_of_an_earlier_run_is_not_overwritten_silently(tmp_path: Path) -> None:
    """FILE.1 is where FILE rotates: one left by an earlier run is refused
    without --force (it would be overwritten at the first rotation) and, with
    it, removed at once (until then it would pass for this run's events)."""
    path = tmp_path / "run.jsonl"
    old = tmp_path / "run.jsonl.1"
    old.write_text("earlier run\n")
    with pytest.raises(RunError, match=r"run\.jsonl\.1 .*exists; pass --force"):
        open_trace(path, max_bytes=2_000)
    assert old.read_text() == "earlier run\n" and not path.exists()
    open_trace(path, force=True, max_bytes=2_000).close()
    assert not old.exists()
    open_trace(tmp_path / "other.jsonl", max_bytes=0).close()  # no cap: no FILE.1 to mind
    (tmp_path / "other.jsonl.1").write_text("kept\n")
    open_trace(tmp_path / "other.jsonl", force=True, max_bytes=0).close()
    assert (tmp_path / "other.jsonl.1").read_text() == "kept\n"


def test_a_trace_file_without_a_cap_does_not_rotate(tmp_path: Path) -> None:
    path = tmp_path / "run.jsonl"
    trace = open_trace(path, max_bytes=0)
    for k in range(200):
        trace(Lifecycle(robot="Emil", t=float(k), what="error", info=(("message", f"m{k}"),)))
    trace.close()
    assert [p.name for p in tmp_path.iterdir()] == ["run.jsonl"]
    assert len(path.read_text().splitlines()) == 200
