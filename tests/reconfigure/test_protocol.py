"""The switch protocol's messages (5.5, cfgplan.runtime.protocol): one module
both sides build and read them with, checked against the docs' protocol page;
a message from another process is read, never trusted."""

from __future__ import annotations

import ast
import json
import re
from pathlib import Path

import pytest

from cfgplan.runtime.monitor import Detection
from cfgplan.runtime.protocol import (
    MAX_BYTES,
    MAX_ID,
    MAX_NAME,
    MAX_TEXT,
    MESSAGES,
    Abort,
    Ack,
    CallError,
    Commit,
    Finish,
    Hello,
    Phase,
    Prepare,
    ProtocolError,
    Ready,
    Report,
    encode,
    read_to_coordinator,
    read_to_robot,
    tag,
    wire_fields,
)
from tests.backends.support import ROOT

PAGE = ROOT / "docs/explanation/switch-protocol.md"
SIDES = (ROOT / "cfgplan/runtime/member.py", ROOT / "cfgplan/reconfigure/network.py")
SIDES += (ROOT / "cfgplan/reconfigure/deployer.py",)

EVERY = [
    Prepare(1, "Emil", "9f2c", {"robot": "Pippi", "channels": [], "calls": []}),
    Commit(2, "Emil", "9f2c"),
    Commit(2, "Emil", "9f2c", {"robot": "Pippi", "channels": [], "calls": []}),
    Abort(3, "Emil", "9f2c"),
    Finish(4, "Emil", "9f2c", "do-cross-door(Emil, Door1)"),
    Hello("Emil", "9f2c"),
    Ack("Pippi", 1, Phase.READY, "9f2c"),
    Ack("Pippi", 1, Phase.REFUSED, "", "no implementation of camera"),
    Report("Pippi", Detection("lost", "Pippi", 12.5, other="Emil", config=3)),
    Ready("Pippi"),
    CallError("Pippi", "F7: transform-info(Pippi, Emil, Door1)", "raised ValueError (impl.py:3)"),
]


@pytest.mark.parametrize("message", EVERY, ids=lambda m: type(m).__name__)
def test_every_message_reads_back_as_written(message: object) -> None:
    payload = encode(message)  # type: ignore[arg-type]
    read = read_to_robot if hasattr(message, "OP") else read_to_coordinator
    assert read(payload) == message


def test_the_wire_format_is_that_of_the_protocol_before_it_was_typed() -> None:
    """Robots of a release before this one read the same JSON."""
    assert json.loads(encode(Prepare(1, "Emil", "e", {"robot": "P"}))) == {
        "op": "prepare",
        "id": 1,
        "from": "Emil",
        "epoch": "e",
        "part": {"robot": "P"},
    }
    assert json.loads(encode(Ack("P", 2, Phase.INSTALLED, "e"))) == {
        "type": "ack",
        "robot": "P",
        "id": 2,
        "phase": "installed",
        "epoch": "e",
    }
    assert json.loads(encode(Commit(2, "Emil", "e"))) == {
        "op": "commit",
        "id": 2,
        "from": "Emil",
        "epoch": "e",
    }


def _table(page: Path = PAGE) -> dict[str, tuple[str, list[str]]]:
    """The page's message table: name -> (tag on the wire, fields)."""
    text = page.read_text(encoding="utf-8")
    section = text.split("## Messages", 1)[1].split("\n## ", 1)[0]
    rows = {}
    for line in section.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 4 and cells[0].startswith("`"):
            fields = re.findall(r"`([^`]+)`", cells[3])
            rows[cells[0].strip("`")] = (cells[2].strip("`"), fields)
    return rows


def test_the_docs_table_of_messages_is_the_module() -> None:
    """Every message and field of the module is on the page, and nothing else."""
    expected = {m.__name__: ('"{}": "{}"'.format(*tag(m)), wire_fields(m)) for m in MESSAGES}
    assert _table() == expected


def test_the_docs_table_check_can_fail(tmp_path: Path) -> None:
    """The check reads the rows it compares: a page whose Ack row lost its
    ``reason`` field, or that lost the Ready row, no longer matches."""
    expected = {m.__name__: ('"{}": "{}"'.format(*tag(m)), wire_fields(m)) for m in MESSAGES}
    text = PAGE.read_text(encoding="utf-8")
    ack = next(line for line in text.splitlines() if line.startswith("| `Ack`"))
    assert "`reason`" in ack
    no_reason = tmp_path / "no-reason.md"
    no_reason.write_text(text.replace(ack, ack.replace("`reason`", "")), encoding="utf-8")
    assert _table(no_reason) != expected and "reason" not in _table(no_reason)["Ack"][1]
    ready = next(line for line in text.splitlines() if line.startswith("| `Ready`"))
    no_ready = tmp_path / "no-ready.md"
    no_ready.write_text(text.replace(ready + "\n", ""), encoding="utf-8")
    assert "Ready" not in _table(no_ready) and _table(no_ready) != expected


def _literals(path: Path) -> list[tuple[int, str]]:
    """String constants of ``path`` that name a message, a phase or the key
    that names them, but for docstrings, trace events' names (``what=``) and
    detections' causes (``how=``)."""
    words = {"op", "type", "phase"}
    words |= {tag(m)[1] for m in MESSAGES} | {p.value for p in Phase}
    tree = ast.parse(path.read_text(encoding="utf-8"))
    skip: set[int] = set()
    for node in ast.walk(tree):
        body = getattr(node, "body", None)
        if isinstance(body, list) and body and isinstance(body[0], ast.Expr):
            skip.add(id(body[0].value))  # a docstring
        if isinstance(node, ast.keyword) and node.arg in ("what", "how"):
            skip.add(id(node.value))
    return [
        (node.lineno, node.value)
        for node in ast.walk(tree)
        if isinstance(node, ast.Constant)
        and isinstance(node.value, str)
        and id(node) not in skip
        and node.value in words
    ]


@pytest.mark.parametrize("path", SIDES, ids=lambda p: p.name)
def test_both_sides_name_no_message_but_through_the_module(path: Path) -> None:
    """No op, type or phase string repeated on either side: one place."""
    assert _literals(path) == []


def test_the_literal_check_can_fail(tmp_path: Path) -> None:
    old = tmp_path / "old.py"
    old.write_text('message = {"op": "prepare", "id": 1}\nif phase == "ready":\n    pass\n')
    assert [v for _, v in _literals(old)] == ["op", "prepare", "ready"]


@pytest.mark.parametrize(
    ("payload", "why"),
    [
        (b"", "not JSON"),
        (b"\xff\xfe", "not JSON"),
        (b"[" * 100_000 + b"]" * 100_000, "not JSON"),
        (b"[1]", "not a JSON object"),
        (b'{"op": "install", "id": 1}', "op is 'install'"),
        (b'{"op": 1}', "op is 1"),
        (b'{"op": "abort", "id": 1e999, "from": "E", "epoch": ""}', "not a configuration id"),
        (b'{"op": "abort", "id": true, "from": "E", "epoch": ""}', "not a configuration id"),
        (b'{"op": "abort", "id": -1, "from": "E", "epoch": ""}', "not a configuration id"),
        (
            b'{"op": "abort", "id": %d, "from": "E", "epoch": ""}' % (MAX_ID + 1),
            "not a configuration id",
        ),
        (b'{"op": "abort", "id": 1, "epoch": ""}', "from is missing"),
        (b'{"op": "abort", "id": 1, "from": ["E"], "epoch": ""}', "not a string"),
        (b'{"op": "prepare", "id": 1, "from": "E", "epoch": ""}', "carries no part"),
        (
            b'{"op": "hello", "from": "%s", "epoch": ""}' % (b"E" * (MAX_NAME + 1)),
            f"at most {MAX_NAME}",
        ),
    ],
)
def test_a_message_to_a_robot_that_is_none_is_refused_with_why(payload: bytes, why: str) -> None:
    with pytest.raises(ProtocolError, match=re.escape(why)):
        read_to_robot(payload)


@pytest.mark.parametrize(
    ("payload", "why"),
    [
        (b'{"type": "ack", "robot": "P", "id": 1, "phase": "done"}', "phase is 'done'"),
        (b'{"type": "ack", "robot": "P", "id": 1, "phase": ["ready"]}', "phase is ['ready']"),
        (
            b'{"type": "ack", "robot": "P", "id": 1, "phase": "refused", "reason": "%s"}'
            % (b"x" * (MAX_TEXT + 1)),
            f"at most {MAX_TEXT}",
        ),
        (b'{"type": "report", "robot": "P", "detection": {"kind": "x"}}', "detection: not a kind"),
        (b'{"type": "report", "robot": "P"}', "detection: not a detection"),
        (b'{"type": "ready", "robot": ""}', "robot is missing or empty"),
        (b'{"type": "ready"}', "robot is missing or empty"),
        (b'{"op": "hello", "from": "E", "epoch": ""}', "type is None"),
    ],
)
def test_a_message_to_the_coordinator_that_is_none_is_refused_with_why(
    payload: bytes, why: str
) -> None:
    with pytest.raises(ProtocolError, match=re.escape(why)):
        read_to_coordinator(payload)


def test_a_message_too_long_is_not_parsed() -> None:
    huge = b'{"type": "ready", "robot": "P", "x": "' + b"x" * MAX_BYTES + b'"}'
    with pytest.raises(ProtocolError, match=f"at most {MAX_BYTES} are read"):
        read_to_coordinator(huge)


def test_texts_written_are_clipped_to_what_is_read() -> None:
    """A refusal's reason may be any length (an implementation's message):
    what is written is always readable."""
    ack = Ack("P", 1, Phase.REFUSED, "", "x" * (10 * MAX_TEXT))
    assert len(ack.reason) == MAX_TEXT and ack.reason.endswith("…")
    assert read_to_coordinator(encode(ack)) == ack
