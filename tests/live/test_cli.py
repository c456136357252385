"""``cfgplan run ... --live [HOST:]PORT``: the option, its errors, and that a
run without it never imports the web stack."""

from __future__ import annotations

import socket
import subprocess
import sys
import threading

import pytest
from typer.testing import CliRunner

import cfgplan.cli.run  # noqa: F401  (loads the command module)
from cfgplan.cli.app import app
from cfgplan.diagnostics import CfgplanError
from tests.backends.support import CROSS, DOMAINS, EXAMPLE_IMPL, ROOT

ARGS = [str(DOMAINS / CROSS[0]), str(DOMAINS / CROSS[1]), "--impl", str(EXAMPLE_IMPL)]
FAST = ["--rate", "100", "--cycles", "5"]


def _live_threads() -> list[threading.Thread]:
    return [t for t in threading.enumerate() if t.name == "cfgplan live page"]


def test_a_run_serves_its_page_and_stops_it() -> None:
    """--live 0 prints the URL of a free port; the server's thread ends with the run."""
    result = CliRunner().invoke(app, ["run", *ARGS, *FAST, "--live", "0"])
    assert result.exit_code == 0, result.output
    assert "live page: http://127.0.0.1:" in result.output
    assert _live_threads() == []


def test_a_bad_address_is_a_usage_error() -> None:
    result = CliRunner().invoke(app, ["run", *ARGS, *FAST, "--live", "localhost:http"])
    assert result.exit_code == 2
    assert "a port is a whole number from 0 to 65535" in result.output


@pytest.mark.slow
def test_a_port_in_use_is_a_clear_error() -> None:
    """Exit 1 with the address and the reason, no traceback."""
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen(1)
        port = taken.getsockname()[1]
        out = subprocess.run(
            [sys.executable, "-m", "cfgplan", "run", *ARGS, *FAST, "--live", str(port)],
            cwd=ROOT,
            capture_output=True,
            text=True,
            timeout=120,
        )
    assert out.returncode == 1, out.stdout + out.stderr
    assert f"cannot serve the live page on 127.0.0.1:{port}" in out.stderr
    assert "Traceback" not in out.stderr


def test_without_aiohttp_the_error_names_the_extra(monkeypatch: pytest.MonkeyPatch) -> None:
    """A user error (exit 1) whose hint is the extra to install."""
    monkeypatch.setitem(sys.modules, "aiohttp", None)  # import aiohttp raises ImportError
    result = CliRunner().invoke(app, ["run", *ARGS, *FAST, "--live", "0"])
    assert isinstance(result.exception, CfgplanError)
    (diagnostic,) = result.exception.diagnostics
    assert diagnostic.message == "--live needs aiohttp, which is not installed"
    assert diagnostic.hint == "pip install 'cfgplan[live]'"


def test_a_run_without_live_never_imports_the_web_stack() -> None:
    """The core install runs without aiohttp: cfgplan run (without --live) and
    the live option's parser do not import it."""
    code = (
        "import sys, cfgplan.cli.run, cfgplan.live.address;"
        "print(sorted(m for m in sys.modules if m.startswith(('aiohttp', 'cfgplan.live.'))))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=60
    )
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "['cfgplan.live.address']"
