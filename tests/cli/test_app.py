"""The ``cfgplan`` command line as a whole: --version, -h, shell
completion, whole one-line summaries, usage lines, cfgplan's own wording for
bad values (never typer's, click's or pydantic's), one wording for a --rank
past the last configuration, a hint for a --goal without parentheses."""

from __future__ import annotations

import json
import pstats
import re
import subprocess
import sys
from importlib.metadata import version
from pathlib import Path

import pytest
import typer

from cfgplan.cli import commands  # noqa: F401  (loads every command module)
from cfgplan.cli.app import COMMANDS as NAMED
from cfgplan.cli.app import app
from tests.backends.support import ROOT
from tests.cli.conftest import Run

DOCKING = ("domains/docking/domain.lisp", "domains/docking/state-kitchen.lisp")
CROSS = ("domains/cross-door/domain.lisp", "domains/cross-door/state-6.2.2-step1.lisp")
COMMANDS = sorted(NAMED)

# What typer, click and pydantic say, and cfgplan must not.
LIBRARY_WORDS = (
    "Value error",
    "Input should be",
    "x>=",
    "<int",
    "<float",
    "<str>",
    "list[str]",
    "{DOMAIN}",
    "{STATE}",
)


def _group() -> typer.core.TyperGroup:
    group = typer.main.get_command(app)
    assert isinstance(group, typer.core.TyperGroup)
    return group


def test_version(cfgplan: Run) -> None:
    out = cfgplan("--version")
    assert out.returncode == 0
    assert out.stdout == f"cfgplan {version('cfgplan')}\n"


@pytest.mark.slow
@pytest.mark.parametrize("command", ["", *COMMANDS])
def test_h_is_help_everywhere(cfgplan: Run, command: str) -> None:
    words = [command] if command else []
    short, long = cfgplan(*words, "-h"), cfgplan(*words, "--help")
    assert short.returncode == long.returncode == 0
    assert short.stdout == long.stdout and "Usage: cfgplan" in short.stdout


def _modules_after(args: list[str]) -> set[str]:
    """The modules loaded once :func:`register` has read the command line ``args``."""
    code = (
        "import json, sys\nfrom cfgplan.cli.app import register\n"
        f"register({args!r})\nprint(json.dumps(sorted(sys.modules)))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=60
    )
    assert out.returncode == 0, out.stderr
    return set(json.loads(out.stdout))


@pytest.mark.slow
def test_a_command_loads_its_own_module_only() -> None:
    """``cfgplan plan`` does not load the runtime, Graphviz or the simulator;
    help, completion and unknown commands load no command ahead: the root group
    loads the commands it lists or is asked for (cfgplan.cli.registry)."""
    group = _group()
    ctx = typer.Context(group, info_name="cfgplan")
    assert group.list_commands(ctx) == COMMANDS  # the one map's names, no other
    others = {f"cfgplan.cli.{c}" for c in COMMANDS if c != "plan"}
    planning = _modules_after(["plan", "-k", "2", "d.lisp", "s.lisp"])
    assert "cfgplan.cli.plan" in planning
    assert not planning & (others | {"cfgplan.runtime", "graphviz", "cfgplan.sim"})
    for args in (["-h"], ["--version"], ["pln", "d.lisp"]):
        assert not _modules_after(args) & (others | {"cfgplan.cli.plan"})


@pytest.mark.slow
def test_shell_completion_as_typer_offers_it(cfgplan: Run) -> None:
    def complete(words: str) -> list[str]:
        env = {
            "_CFGPLAN_COMPLETE": "complete_bash",
            "COMP_WORDS": words,
            "COMP_CWORD": str(len(words.split()) - 1),
        }
        out = cfgplan(env=env)
        assert out.returncode == 0, out.stderr
        return out.stdout.split()

    assert complete("cfgplan pl") == ["plan"]
    assert complete("cfgplan plan d s --format j") == ["json", "jsonl"]
    assert complete("cfgplan emit d s --lang p") == ["python"]
    assert "--rank" in complete("cfgplan render d s --ra")
    # typer reads a shell's name after --show-completion only with its shell
    # detection off; on, it looks for a shell among the parent processes,
    # and a CI job started without one has none.
    off = {"_TYPER_COMPLETE_TEST_DISABLE_SHELL_DETECTION": "1"}
    script = cfgplan("--show-completion", "bash", env=off)
    assert script.returncode == 0 and "_CFGPLAN_COMPLETE" in script.stdout


def test_help_shows_whole_one_line_summaries(cfgplan: Run) -> None:
    """On an 80-column terminal each command's summary is whole, on its line."""
    out = cfgplan("--help", env={"COLUMNS": "80"})
    listing = out.stdout.split("Commands:\n", 1)[1].splitlines()
    shown = {line.split()[0]: line.split(None, 1)[1] for line in listing if line.strip()}
    group = _group()
    ctx = typer.Context(group, info_name="cfgplan")
    for name in COMMANDS:
        summary = group.get_command(ctx, name).short_help
        assert summary and summary.endswith(".")
        assert shown[name] == summary, name
    assert len(shown) == len(COMMANDS)  # no summary ran onto a second line


@pytest.mark.parametrize("command", COMMANDS)
def test_usage_and_help_speak_cfgplan(cfgplan: Run, command: str) -> None:
    out = cfgplan(command, "-h", env={"COLUMNS": "200"})
    usage = out.stdout.splitlines()[0]
    arguments = {
        "simulate": "EXPERIMENT",
        "record": "TRACE",
        "report": r"RUN\.\.\.",
        "keys": r"COMMAND \[ARGS\]\.\.\.",
        "router": "",
        "launch": r"DOMAIN STATE --impl IMPL \[RUN OPTIONS\]\.\.\.",  # run's options go on
    }.get(command, r"DOMAIN (STATE|\[STATE\])")
    assert re.fullmatch(rf"Usage: cfgplan {command} \[OPTIONS\] ?{arguments}", usage)
    assert not [w for w in LIBRARY_WORDS if w in out.stdout]


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["plan", *DOCKING, "--format", "yaml"], "'yaml' is not a format: choose table, lisp"),
        (["plan", *DOCKING, "-k", "abc"], "'abc' is not a whole number"),
        (["plan", *DOCKING, "-k", "0"], "0: must be 1 or more"),
        (["plan", *DOCKING, "--time-limit", "-1"], "-1: must be at least 0"),
        (["plan", *DOCKING, "--time-limit", "soon"], "'soon' is not a number"),
        (["plan", *DOCKING, "--weights", "robot=x"], "bad weight 'robot=x'"),
        (
            ["plan", *DOCKING, "--weights", "local=1.00000000000000000001"],
            "1.00000000000000000001 has more digits than a number keeps: it would be read as 1.0",
        ),
        (
            ["run", *DOCKING, "--impl", "x", "--rate", "10.000000000000000000001"],
            "it would be read as 10.0",
        ),
        (["plan", *DOCKING, "--rank", "2", "-k", "3"], "-k and --all list several"),
        (["plan", *DOCKING, "--all", "-k", "3"], "lists that many; --all lists every one"),
        (
            ["render", *DOCKING, "-o", "x.svg", "--hierarchy", "--rank", "2"],
            "--hierarchy draws the methods",
        ),
        (["render", *DOCKING, "-o", "x.dot", "--rank", "first"], "'first' is not a whole"),
        (["emit", *DOCKING, "-o", "out", "--lang", "c"], "'c' is not a language: choose lisp"),
        (["run", *DOCKING, "--impl", "x", "--rate", "nan"], "nan: must be a finite number"),
        (["run", *DOCKING, "--impl", "x", "--transport", "q"], "'q' is not a transport"),
        (["run", *DOCKING, "--impl", "x", "--cycles", "-1"], "-1: must be 0 or more"),
        (["run", *DOCKING, "--impl", "x", "--hold", "0"], "0: must be more than 0"),
    ],
)
def test_bad_values_get_cfgplan_wording(cfgplan: Run, args: list[str], message: str) -> None:
    out = cfgplan(*args)
    assert out.returncode == 2, out.stderr
    assert message in out.stderr
    assert not [w for w in LIBRARY_WORDS if w in out.stderr], out.stderr
    assert "Traceback" not in out.stderr


@pytest.mark.parametrize(
    "args",
    [
        ["plan", *DOCKING],
        ["render", *DOCKING, "-o", "never.dot"],
        ["emit", *DOCKING, "-o", "never"],
        ["run", *DOCKING, "--impl", "examples/cross-door/impl.py"],
    ],
    ids=["plan", "render", "emit", "run"],
)
def test_rank_past_the_last_has_one_wording(cfgplan: Run, args: list[str]) -> None:
    out = cfgplan(*args, "--rank", "99")
    assert out.returncode == 3
    assert out.stderr == (
        "cfgplan: error: do-dock(Vacu, Charger1) has 3 configurations, none of rank 99\n"
        "  hint: --rank 1 to 3\n"
    )
    assert out.stdout == ""


def test_plan_rank_shows_that_configuration_alone(cfgplan: Run) -> None:
    """6.2.2: the configuration of rank 2 costs 47."""
    out = cfgplan("plan", *CROSS, "--rank", "2", "--format", "json")
    assert out.returncode == 0, out.stderr
    doc = json.loads(out.stdout)
    assert [(c["rank"], c["cost"]) for c in doc["configurations"]] == [(2, 47)]
    table = cfgplan("plan", *CROSS, "--rank", "2").stdout
    assert re.search(r"│\s+2 │\s+47 │", table) and "│    1 │" not in table


def test_a_goal_without_parentheses_gets_a_hint(cfgplan: Run) -> None:
    out = cfgplan("plan", *DOCKING, "--goal", "do-dock Vacu Charger1")
    assert out.returncode == 1
    assert out.stderr.splitlines() == [
        "--goal:1:7: error: a goal is a method instance in parentheses",
        "    1 | (goal do-dock Vacu Charger1)",
        "      |       ^^^^^^^^^^^^^^^^^^^^^",
        "  hint: add the parentheses: --goal '(do-dock Vacu Charger1)'",
    ]


def _console(args: list[str]) -> subprocess.CompletedProcess[str]:
    """The console script's :func:`~cfgplan.cli.app.console` on ``args``, in a
    process of its own, stdout a pipe, with an exit handler that says when the
    interpreter was torn down as usual."""
    code = (
        "import atexit, sys\n"
        "atexit.register(lambda: sys.stderr.write('torn down\\n'))\n"
        f"sys.argv = ['cfgplan', *{args!r}]\n"
        "from cfgplan.cli.app import console\nconsole()\n"
    )
    return subprocess.run(
        [sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=120
    )


@pytest.mark.slow
def test_a_planning_command_leaves_at_once_with_its_output_whole(cfgplan: Run) -> None:
    """``plan`` (a QUICK_EXIT command) ends without the interpreter's teardown
    (app._leave: no exit handler runs), yet what it printed through the pipe
    is whole, the same as in-process, and its exit status is kept: 0, or 1
    for a file that is not there (its message on stderr). ``--version`` is no
    such command: torn down as usual."""
    quick = _console(["plan", "--format", "json", *CROSS])
    assert quick.returncode == 0, quick.stderr
    assert "torn down" not in quick.stderr
    assert json.loads(quick.stdout) == json.loads(
        cfgplan("plan", "--format", "json", *CROSS).stdout
    )
    missing = _console(["plan", CROSS[0], "domains/cross-door/no-such-state.lisp"])
    assert missing.returncode == 1
    assert "no such file" in missing.stderr and "torn down" not in missing.stderr
    usual = _console(["--version"])
    assert usual.returncode == 0 and usual.stdout.startswith("cfgplan ")
    assert "torn down" in usual.stderr


def test_a_profiled_planning_command_ends_as_usual(tmp_path: Path) -> None:
    """Under ``python -m cProfile -o FILE -m cfgplan plan ...`` the profile is
    written: a watched process is not ended at once (the profiler writes it
    when the command returns)."""
    profile = tmp_path / "plan.prof"
    out = subprocess.run(
        [sys.executable, "-m", "cProfile", "-o", str(profile), "-m", "cfgplan", "plan", *CROSS],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert out.returncode == 0, out.stderr
    assert profile.stat().st_size > 0
    stats = pstats.Stats(str(profile))
    assert any(name == "console" for _, _, name in stats.stats)  # type: ignore[attr-defined]
