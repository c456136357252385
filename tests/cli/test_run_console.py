"""``cfgplan run``'s console: what matters, not a line per cycle.

By default a run shows a compact status and every loss, stale input, failure
and switch with its cause; an action's data when it starts to receive it (and
again after an interruption), every cycle only with ``--verbose``. A scripted
fault is tagged ``[injected]``, not with the implementations' file as if they
had failed. Without a terminal (here: the test runner's streams) the console
is plain lines, the same from one run to the next.
"""

from __future__ import annotations

import io
import re

import pytest
from typer.testing import CliRunner

import cfgplan.cli.run  # noqa: F401  (loads the command module)
from cfgplan.cli.app import app
from cfgplan.runtime import Call, Presence
from cfgplan.runtime.console import Printer
from cfgplan.runtime.events import Lifecycle
from tests.backends.support import DOMAINS, EXAMPLE_IMPL

STEP2 = [str(DOMAINS / "cross-door" / name) for name in ("domain.lisp", "state-6.2.2-step2.lisp")]
FAULT = ["--impl", str(EXAMPLE_IMPL), "--rate", "0", "--cycles", "250"]
FAULT += ["--inject", "fail compass(Emil) at cycle 20"]
RECEIVED = "Emil F3 cross-door(Emil, Door1) received "


def _run(*extra: str) -> tuple[list[str], list[str]]:
    result = CliRunner().invoke(app, ["run", *STEP2, *FAULT, *extra])
    assert result.exit_code == 0, result.output
    return result.stdout.splitlines(), result.stderr.splitlines()


def test_the_console_shows_what_matters_not_every_cycle() -> None:
    out, err = _run()
    received = [line for line in out if RECEIVED in line]
    # when cross-door starts to receive, and again once the switch is through
    assert [line.split(":")[0] for line in received] == ["cycle 2", "cycle 22"]
    switch = next(line for line in out if ": switch " in line)
    assert switch.startswith(
        "cycle 20: Emil: switch 1 (compass(Emil) failed): cost 44 -> 47 (fallback); stopped "
    )
    assert "cycle 20: Emil: failure of compass(Emil) (injected, seen by Emil); " in "\n".join(out)
    status = [line for line in out if ": status: " in line]
    assert [line.split(":")[0] for line in status] == ["cycle 100", "cycle 200"]
    assert status[0] == (
        "cycle 100: status: cycles Emil 100, Pippi 100; 1 switch, now cost 47; 1 failure; "
        "cross-door(Emil, Door1) ran 98 times, "
        "last received pos(Emil, Door1) = [4.412, 0.729], orient(Emil, Door1) = 1.271"
    )
    assert len(out) < 30  # not a line per cycle (250 cycles)
    (fault,) = [line for line in err if "failed" in line]
    assert fault == (
        "cfgplan: cycle 20: Emil F10 compass(Emil) failed: injected fault "
        "(fail compass(Emil) at cycle 20) [injected]"
    )
    assert str(EXAMPLE_IMPL) not in "\n".join(err)


def test_verbose_shows_every_cycle_and_the_plain_console_is_deterministic() -> None:
    out, _ = _run("--verbose")
    received = [line for line in out if RECEIVED in line]
    assert len(received) == 248  # every cycle but the first and the one of the switch
    assert _run() == _run()


def test_a_failure_of_the_implementation_is_tagged_with_its_file() -> None:
    out, err = io.StringIO(), io.StringIO()
    printer = Printer(False, "impl.py", out, err)
    head = {"robot": "Emil", "cycle": 3, "label": "F10", "name": "compass", "args": ("Emil",)}
    printer(Call(**head, status="error", error="the implementation raised E"))  # type: ignore[arg-type]
    printer(Call(**head, status="error", error="injected fault (x)", failure="injected"))  # type: ignore[arg-type]
    assert err.getvalue().splitlines() == [
        "cfgplan: cycle 3: Emil F10 compass(Emil) failed: the implementation raised E [impl.py]",
        "cfgplan: cycle 3: Emil F10 compass(Emil) failed: injected fault (x) [injected]",
    ]
    assert out.getvalue() == ""


def test_text_from_another_process_cannot_drive_the_terminal() -> None:
    """A helper's error text (``call-error``) is printed by the coordinator:
    an escape sequence in it is shown escaped, never written raw."""
    out, err = io.StringIO(), io.StringIO()
    printer = Printer(False, "impl.py", out, err)
    said = "Pippi F7 transform-info(Pippi): boom \x1b[2J\x1b]0;owned\x07"
    printer(Lifecycle(robot="Emil", t=0.0, what="error", info=(("message", said),)))
    shown = out.getvalue() + err.getvalue()
    assert "boom" in shown and "\x1b" not in shown and "\x07" not in shown
    assert "\\x1b[2J" in shown


def test_errors_of_one_kind_are_shown_three_times_then_counted() -> None:
    """500 oversized messages on one channel printed 500 lines. Now
    each kind of error (its text before the first ``": "``: the channel) is
    shown three times, then counted in the status; a flood of kinds from the
    network is told apart only up to a bound."""
    out, err = io.StringIO(), io.StringIO()
    printer = Printer(False, "impl.py", out, err, status_every=1)

    def error(said: str) -> None:
        printer(Lifecycle(robot="Emil", t=0.0, what="error", info=(("message", said),)))

    for n in range(500):
        error(f"channel F7->F3 (pos Emil Door1): a message of {n} bytes; dropped")
    error("channel F9->F3 (orient Emil Door1): a message of 9 bytes; dropped")
    for n in range(200):
        error(f"robot{n}: forged")
    lines = err.getvalue().splitlines()
    assert lines[:4] == [
        "cfgplan: cycle 0: Emil: channel F7->F3 (pos Emil Door1): a message of 0 bytes; dropped",
        "cfgplan: cycle 0: Emil: channel F7->F3 (pos Emil Door1): a message of 1 bytes; dropped",
        "cfgplan: cycle 0: Emil: channel F7->F3 (pos Emil Door1): a message of 2 bytes; dropped",
        "cfgplan: further errors of channel F7->F3 (pos Emil Door1) are only counted "
        "(status; --trace has each)",
    ]
    orient = "channel F9->F3 (orient Emil Door1): a message of 9 bytes; dropped"
    assert lines[4] == f"cfgplan: cycle 0: Emil: {orient}"
    assert len(lines) < 5 + 64 * 4 + 4
    printer.cycle(1)
    assert "701 errors" in out.getvalue()


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_on_a_terminal_the_status_is_drawn_in_place_and_lines_go_above_it(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setenv("TERM", "xterm")
    monkeypatch.setenv("COLUMNS", "80")
    out, err = _Terminal(), _Terminal()
    printer = Printer(False, "impl.py", out, err)
    printer.start()
    head = {"robot": "Pippi", "label": "F3", "name": "cross-door", "args": ("Pippi", "Door1")}
    pos = ((("pos", "Pippi", "Door1"), (1.0, 2.0)),)
    for cycle in (1, 2):
        printer(Call(**head, cycle=cycle, status="ran", action=True, inputs=pos))  # type: ignore[arg-type]
    printer(Presence(robot="Pippi", cycle=2, t=1.0, other="Emil", alive=False))
    printer(Call(**head, cycle=3, status="error", error="raised E"))  # type: ignore[arg-type]
    printer.stop()
    drawn = out.getvalue()
    assert "\x1b[2K" in drawn  # drawn, then erased (transient), by cursor control
    shown = re.sub(r"\x1b\[[0-9;?]*[a-zA-Z]", "", drawn)
    # one line, cut short of the terminal's 80 columns
    assert " s │ cycles Pippi 3 │ 1 failure │ 1 robot lost │ cross-door(Pippi, Door1…\n" in shown
    assert "cycle 2: Pippi: robot Emil lost" in shown
    assert "failed: raised E [impl.py]" in shown  # one terminal: above the status too
    assert shown.count(" received ") == 1 and err.getvalue() == ""
