"""The fuzzer's worker (:mod:`benchmarks.fuzz`): runs inputs in process.

``python -m benchmarks.fuzz_worker --time-limit S --dump FILE`` reads inputs
(JSON lines: a domain and a state, base64) on stdin and puts each through
cfgplan's command line, in this process: ``check``; if that passes ``plan``
and ``render --hierarchy``; if planning ends (found or none admissible) both
``emit`` and ``render``. It reports the start and the outcome of each command
on stdout: ``success`` (exit 0 or 3), ``clean`` (exit 1 or 2 with a message),
``memory`` (cfgplan's out-of-memory message), ``traceback`` (an exception
escaping ``main``), ``escape`` (a file outside ``-o``) or ``invalid`` (emitted
Python that does not compile). A command still running at its time limit has
its stack dumped to FILE by faulthandler, and the worker exits.
"""

from __future__ import annotations

import argparse
import base64
import contextlib
import faulthandler
import functools
import io
import json
import os
import resource
import sys
import tempfile
import traceback
from pathlib import Path
from typing import Any

ABSOLUTE_BAIT = "/tmp/cfgplan-fuzz-abs"
"""A hostile robot name of the inputs: emit once wrote ``ABSOLUTE_BAIT.py``."""
"""A hostile robot name of the inputs; a file starting so would be an escape."""


def commands(folder: Path) -> list[tuple[str, list[str], str]]:
    """(name, arguments, what must have succeeded first) for one input."""
    d, s, out = (
        str(folder / "domain.lisp"),
        str(folder / "state.lisp"),
        folder / "a" / "b",
    )
    return [
        ("check", ["check", d, s], ""),
        ("plan", ["plan", d, s, "-k", "3", "--format", "json"], "check"),
        (
            "hierarchy",
            ["render", d, s, "--hierarchy", "-o", str(out / "h.dot")],
            "check",
        ),
        (
            "emit-lisp",
            ["emit", d, s, "--lang", "lisp", "-o", str(out / "lisp")],
            "plan",
        ),
        (
            "emit-python",
            ["emit", d, s, "--lang", "python", "-o", str(out / "py")],
            "plan",
        ),
        ("render", ["render", d, s, "-o", str(out / "c.dot")], "plan"),
    ]


# -- the worker: runs inputs in process --------------------------------------------------


def _run_cli(args: list[str]) -> tuple[str, str]:
    """Run ``cfgplan ARGS`` through its ``main``; (kind, stderr or traceback)."""
    from cfgplan.cli.app import main

    sys.argv = ["cfgplan", *args]
    err = io.StringIO()
    try:
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
            main()
        code: object = 0
    except SystemExit as exc:
        code = exc.code
    except Exception:
        return "traceback", traceback.format_exc()
    if code in (0, 3, None):
        return "success", ""
    message = err.getvalue()
    if "error: out of memory" in message:
        return "memory", message
    return ("clean" if message.strip() else "traceback"), message or f"exit {code}, no message"


def _check_outputs(name: str, folder: Path) -> tuple[str, str] | None:
    """An escape (a file outside -o) or emitted Python that does not compile."""
    inside = folder / "a" / "b"
    for path in folder.rglob("*"):
        if path.is_file() and path.parent != folder and inside not in path.parents:
            return "escape", f"{name} wrote {path}"
    for suffix in (".py", ".lisp", ".txt", ".dot", ""):
        if os.path.lexists(ABSOLUTE_BAIT + suffix):
            return "escape", f"{name} wrote {ABSOLUTE_BAIT + suffix}"
    if name == "emit-python":
        for path in (inside / "py").glob("*.py"):
            try:
                compile(path.read_bytes(), str(path), "exec")
            except (SyntaxError, ValueError) as exc:
                return "invalid", f"{path.name}: {exc}"
    return None


def worker(time_limit: float, dump: str) -> None:
    """Read inputs (JSON lines) on stdin, report each command on stdout."""
    protocol = os.fdopen(os.dup(1), "w", buffering=1)
    null = os.open(os.devnull, os.O_WRONLY)
    os.dup2(null, 1)  # what C code prints goes nowhere
    stack = open(dump, "w")  # noqa: SIM115 - open for the worker's lifetime

    def send(message: dict[str, Any]) -> None:
        protocol.write(json.dumps(message) + "\n")

    # Reading is pure: each file of an input is parsed once, not once per command.
    # And typer builds its click command anew on every call (10 ms): build it once.
    import typer.main

    from cfgplan.cli import app
    from cfgplan.cli import commands as registered  # noqa: F401
    from cfgplan.syntax import reader

    command = typer.main.get_command(app.app)
    app.app = lambda **kwargs: command.main(**kwargs)  # type: ignore[assignment]

    parsed = functools.lru_cache(maxsize=4)(reader.parse)
    reader.parse = parsed

    for line in sys.stdin:
        job = json.loads(line)
        with tempfile.TemporaryDirectory(prefix="cfgplan-fuzzing-") as tmp:
            folder = Path(tmp)
            (folder / "domain.lisp").write_bytes(base64.b64decode(job["domain"]))
            (folder / "state.lisp").write_bytes(base64.b64decode(job["state"]))
            (folder / "a" / "b").mkdir(parents=True)
            passed = {""}
            for name, args, needs in commands(folder):
                if needs not in passed:
                    continue
                send({"start": name})
                stack.seek(0)
                stack.truncate()
                faulthandler.dump_traceback_later(time_limit, exit=True, file=stack)
                kind, detail = _run_cli(args)
                faulthandler.cancel_dump_traceback_later()
                found = _check_outputs(name, folder) if kind == "success" else None
                kind, detail = found or (kind, detail)
                if kind == "success":
                    passed.add(name)
                send({"done": name, "kind": kind, "detail": detail[-6000:]})
        parsed.cache_clear()
        send({"end": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss})


def main() -> None:
    parser = argparse.ArgumentParser(description="the fuzzer's worker (benchmarks.fuzz)")
    parser.add_argument("--time-limit", type=float, default=5.0)
    parser.add_argument("--dump", required=True)
    args = parser.parse_args()
    worker(args.time_limit, args.dump)


if __name__ == "__main__":
    main()
