"""What a run prints and records: values shown safely, the --trace file (JSON
lines) and where it may be written."""

from __future__ import annotations

import io
import json
import os
from pathlib import Path

import pytest

from cfgplan.runtime import Call, Presence, RunError, show
from cfgplan.runtime.console import WAIT_NOTICE, Printer
from cfgplan.runtime.trace import describe, show_checked
from cfgplan.runtime.tracefile import open_trace


class Bad:
    def __repr__(self) -> str:
        raise ValueError("boom")


def _call(**fields: object) -> Call:
    base: dict[str, object] = dict(
        robot="Pippi", cycle=2, t=1.5, label="F3", name="cross-door", args=("Pippi", "Door1")
    )
    base.update(fields)
    return Call(**base)  # type: ignore[arg-type]


def test_show_is_compact_and_deterministic() -> None:
    assert show((1.5, -0.00001)) == "(1.500, 0.000)"
    assert show({"Door1": [1.0, None, True]}) == "{'Door1': [1.000, None, True]}"
    assert show((1,)) == "(1,)"


# These used to raise out of the trace printer.


def test_a_value_that_contains_itself_is_shown_with_dots() -> None:
    loop: list[object] = [1.0]
    loop.append(loop)
    again: dict[str, object] = {}
    again["me"] = again
    assert show(loop) == "[1.000, ...]"
    assert show(again) == "{'me': ...}"


def test_a_failing_repr_is_shown_as_a_placeholder_and_blamed() -> None:
    text, problem = show_checked([Bad()])
    assert text == "[<Bad object; its __repr__ raised ValueError: boom>]"
    assert problem == "its __repr__ raised ValueError: boom"


def test_the_printer_blames_the_implementation_once_naming_file_and_functionality() -> None:
    out, err = io.StringIO(), io.StringIO()
    printer = Printer(verbose=True, source="impl.py", out=out, err=err)
    event = _call(status="ran", action=True, inputs=((("pos", "Pippi", "Door1"), Bad()),))
    printer(event)
    printer(event)
    assert (
        out.getvalue().splitlines()
        == [
            "cycle 2: Pippi F3 cross-door(Pippi, Door1) received pos(Pippi, Door1) = "
            "<Bad object; its __repr__ raised ValueError: boom>"
        ]
        * 2
    )
    assert err.getvalue().splitlines() == [
        "cfgplan: warning: F3 cross-door on Pippi: pos(Pippi, Door1): its __repr__ raised "
        "ValueError: boom (implementations: impl.py)"
    ]


def test_the_printer_shows_a_functionalitys_first_failures_then_counts() -> None:
    out, err = io.StringIO(), io.StringIO()
    printer = Printer(verbose=False, source="impl.py", out=out, err=err)
    for _ in range(5):
        printer(_call(status="error", error="the implementation raised OSError: gone"))
    printer(Presence(robot="Pippi", cycle=7, t=2.0, other="Emil", alive=False))
    lines = err.getvalue().splitlines()
    assert lines[0] == (
        "cfgplan: cycle 2: Pippi F3 cross-door(Pippi, Door1) failed: the implementation "
        "raised OSError: gone [impl.py]"
    )
    assert len(lines) == 4 and lines[3].startswith("cfgplan: further failures of F3")
    assert out.getvalue() == "cycle 7: Pippi: robot Emil lost\n"
    assert printer.failed


def test_a_failure_placed_in_the_implementations_file_names_it_once() -> None:
    """ "(impl.py:11 in localise) [impl.py]" named the file twice; the tag stays
    where the place is elsewhere (a module the implementations import) or unknown."""
    out, err = io.StringIO(), io.StringIO()
    printer = Printer(verbose=False, source="/x/impl.py", out=out, err=err)
    printer(_call(status="error", error="the implementation raised E: no (/x/impl.py:11 in f)"))
    printer(
        _call(label="F4", status="error", error="the implementation raised E (/x/lib.py:3 in g)")
    )
    first, second = err.getvalue().splitlines()
    assert first.endswith("failed: the implementation raised E: no (/x/impl.py:11 in f)")
    assert second.endswith("failed: the implementation raised E (/x/lib.py:3 in g) [/x/impl.py]")


def test_the_printer_says_what_a_functionality_waits_for_then_that_it_runs_again() -> None:
    """After WAIT_NOTICE calls in a row without its data, once; and
    when the data comes, once; a short wait is not worth a line."""
    out, err = io.StringIO(), io.StringIO()
    printer = Printer(verbose=False, source="impl.py", out=out, err=err)
    pos = (("pos", "Pippi", "Door1"),)
    for cycle in range(1, WAIT_NOTICE + 3):
        printer(_call(cycle=cycle, status="waiting", waiting=pos, action=True))
    printer(_call(cycle=WAIT_NOTICE + 3, status="ran", action=False))
    for cycle in range(WAIT_NOTICE + 4, WAIT_NOTICE + 6):  # two calls: not said
        printer(_call(cycle=cycle, status="waiting", waiting=pos, action=True))
    printer(_call(cycle=WAIT_NOTICE + 6, status="ran", action=False))
    assert out.getvalue().splitlines() == [
        f"cycle {WAIT_NOTICE}: Pippi F3 cross-door(Pippi, Door1) waits for pos(Pippi, Door1) "
        f"({WAIT_NOTICE} calls in a row so far)",
        f"cycle {WAIT_NOTICE + 3}: Pippi F3 cross-door(Pippi, Door1) runs again",
    ]
    assert err.getvalue() == ""


def test_describe_says_why_a_functionality_did_not_run() -> None:
    assert describe(_call(status="stale", stale=(("pos", "Pippi", "Door1"),))).endswith(
        "cross-door(Pippi, Door1) does not run: stale pos(Pippi, Door1)"
    )
    assert describe(_call(status="busy")).endswith("does not run: its last call is still running")


def _strict(line: str) -> object:
    def refuse(constant: str) -> object:
        raise ValueError(f"{constant} is not JSON")

    return json.loads(line, parse_constant=refuse)


@pytest.mark.parametrize("force", [False, True])
def test_a_trace_is_its_owners_only_and_every_line_json(tmp_path: Path, force: bool) -> None:
    """Measured: traces were written 0644 (every value of the run, readable
    by anyone on the robot), and a NaN a functionality computed was written
    as a bare NaN, which is not JSON. A trace is made 0600, also one that
    --force truncates; a float that is not finite is written as a string."""
    path = tmp_path / "t.jsonl"
    if force:
        path.write_text("an earlier run\n")
        path.chmod(0o644)
    trace = open_trace(path, force=force)
    nan, inf = float("nan"), float("inf")
    trace(_call(status="ran", inputs=((("pos", "Pippi", "Door1"), [nan, inf, -inf, 0.5]),)))
    trace.close()
    assert path.stat().st_mode & 0o777 == 0o600
    (line,) = path.read_text().splitlines()
    record = _strict(line)
    assert isinstance(record, dict)
    assert record["inputs"][0]["value"] == ["NaN", "Infinity", "-Infinity", 0.5]


def test_trace_lines_follow_the_schema(tmp_path: Path) -> None:
    trace = open_trace(tmp_path / "t.jsonl")
    trace(_call(status="ran", action=True, inputs=((("pos", "Pippi", "Door1"), (0.5, Bad())),)))
    trace(Presence(robot="Pippi", cycle=3, t=4.0, other="Emil", alive=True))
    trace.close()
    first, second = (json.loads(x) for x in (tmp_path / "t.jsonl").read_text().splitlines())
    assert first == {
        "event": "call",
        "robot": "Pippi",
        "t": 1.5,
        "cycle": 2,
        "label": "F3",
        "functionality": "cross-door",
        "args": ["Pippi", "Door1"],
        "status": "ran",
        "inputs": [
            {
                "data": ["pos", "Pippi", "Door1"],
                "value": [
                    0.5,
                    {
                        "$type": "tests.runtime.test_trace.Bad",
                        "$repr": "<Bad object; its __repr__ raised ValueError: boom>",
                    },
                ],
            }
        ],
        "outputs": [],
    }
    assert second == {
        "event": "robot-seen",
        "robot": "Pippi",
        "t": 4.0,
        "cycle": 3,
        "other": "Emil",
    }


# For traces: where --trace may write.


def test_an_existing_trace_is_never_overwritten_without_force(tmp_path: Path) -> None:
    path = tmp_path / "run.jsonl"
    path.write_text("precious\n")
    with pytest.raises(RunError, match="exists; pass --force to overwrite it"):
        open_trace(path)
    assert path.read_text() == "precious\n"
    open_trace(path, force=True).close()
    assert path.read_text() == ""


def test_a_dangling_symlink_is_not_written_through(tmp_path: Path) -> None:
    target = tmp_path / "elsewhere" / "created.jsonl"
    target.parent.mkdir()
    link = tmp_path / "trace.jsonl"
    link.symlink_to(target)
    for force in (False, True):
        with pytest.raises(RunError, match=r"symbolic link to .*which does not exist"):
            open_trace(link, force)
    assert not target.exists()


def test_a_trace_that_cannot_be_written_is_a_clear_error(tmp_path: Path) -> None:
    with pytest.raises(RunError, match="is a directory"):
        open_trace(tmp_path)
    with pytest.raises(RunError, match=r"cannot write the trace file .*No such file or directory"):
        open_trace(tmp_path / "missing" / "t.jsonl")
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    with pytest.raises(RunError, match="not a regular file"):
        open_trace(fifo, force=True)
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o500)
    try:
        # root may write anywhere but in sysfs
        where = locked if not os.access(locked, os.W_OK) else Path("/sys")
        if not where.is_dir():
            pytest.skip("no unwritable folder here")
        with pytest.raises(RunError, match=r"cannot write the trace file .*Permission denied"):
            open_trace(where / "cfgplan-test-trace.jsonl")
    finally:
        locked.chmod(0o700)


def test_a_trace_that_fails_later_stops_tracing_and_says_why(tmp_path: Path) -> None:
    if not Path("/dev/full").exists():
        pytest.skip("no /dev/full here")
    trace = open_trace(tmp_path / "t.jsonl")
    trace._stream = open("/dev/full", "w")  # noqa: SIM115  (a disk that is full)
    trace(_call(status="waiting"))
    trace.flush()
    assert trace.failed is not None and "No space left on device; tracing stopped" in trace.failed
    trace(_call(status="waiting"))  # no exception: tracing has stopped
    trace.close()
