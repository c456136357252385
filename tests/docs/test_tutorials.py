"""The tutorials run: every ``sh`` block of ``docs/tutorials/*.md`` works and prints
what the ``text`` block after it shows (the convention: :mod:`tests.docs.tutorials`)."""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest

from tests.docs.tutorials import ROOT, TUTORIALS, Step, blocks, missing, run, scratch, steps

PAGES = sorted(TUTORIALS.glob("*.md"))
ROS2 = {"ros2-base"}
"""The tutorials with real ROS 2 nodes (rclpy): without it they are skipped, under CI failed."""


EXPERIMENTS = ("plan", "render", "emit", "run-two-processes", "failure-and-switch", "simulate")
"""The tutorials of the thesis's experiments (docs/tutorials/): each has commands to run."""


def _report(page: Path, step: Step, why: str, out: subprocess.CompletedProcess[str]) -> str:
    return (
        f"{page.relative_to(TUTORIALS.parents[1])}:{step.line}: {why}\n"
        f"--- the block ---\n{step.script}"
        f"--- stdout ---\n{out.stdout}--- stderr ---\n{out.stderr}"
    )


def test_every_experiment_tutorial_has_commands_to_run() -> None:
    for name in EXPERIMENTS:
        page = TUTORIALS / f"{name}.md"
        assert steps(page.read_text(encoding="utf-8")), f"{page.name}: no sh block"


@pytest.mark.parametrize(
    "page",
    [  # the plan tutorial runs in the fast set, the one with a real ROS 2 node in the
        # ros2 set (it needs rclpy: .ci/run installs it), every other one in the slow set
        p
        if p.stem == "plan"
        else pytest.param(p, marks=pytest.mark.ros2)
        if p.stem in ROS2
        else pytest.param(p, marks=pytest.mark.slow)
        for p in PAGES
    ],
    ids=[p.stem for p in PAGES],
)
def test_tutorial_runs(page: Path, tmp_path: Path) -> None:
    if page.stem in ROS2:
        from tests.ros2 import realros

        realros.rclpy()
    folder = scratch(tmp_path)
    for step in steps(page.read_text(encoding="utf-8")):
        out = run(step, folder)
        if out.returncode != 0:
            pytest.fail(_report(page, step, f"exit status {out.returncode}", out), False)
        lost = missing(step.expected, out.stdout)
        if lost is not None:
            pytest.fail(_report(page, step, f"expected line not printed: {lost!r}", out), False)
    # What the page made, run from the top of a clone, is not left for git status.
    made = sorted(
        p.name + ("/" if p.is_dir() else "")
        for p in folder.iterdir()
        if p.name not in ("domains", "examples")
    )
    if made:
        ignored = subprocess.run(
            ["git", "-C", str(ROOT), "check-ignore", "--no-index", *made],
            capture_output=True,
            text=True,
        ).stdout.split()
        assert ignored == made, f"{page.name} leaves files git does not ignore: {made}"


# -- the runner itself --------------------------------------------------------

PAGE = """# A page

```sh
echo one > f.txt
printf 'a  \\nb\\nc\\n'
if true; then
  printf '  d\\n'
fi
```

```text
a
...
c
  d
```

Prose.

```text
not expected output: prose stands between
```

```console
$ not run
```

    ```sh
    cat f.txt
    ```
````sh
echo four
````
"""


def test_blocks_and_expected_lines() -> None:
    found = steps(PAGE)
    assert [s.script for s in found] == [
        "echo one > f.txt\nprintf 'a  \\nb\\nc\\n'\nif true; then\n  printf '  d\\n'\nfi\n",
        "cat f.txt\n",
        "echo four\n",
    ]
    assert [s.expected for s in found] == [("a", "...", "c", "  d"), (), ()]
    assert [b.info for b in blocks(PAGE)] == ["sh", "text", "text", "console", "sh", "sh"]


def test_blocks_share_a_folder_and_output_is_matched_by_whole_lines(tmp_path: Path) -> None:
    first, second, _ = steps(PAGE)
    out = run(first, tmp_path)
    assert out.returncode == 0, out.stderr
    assert missing(first.expected, out.stdout) is None
    assert missing(("c", "a"), out.stdout) == "a"  # in order
    assert missing(("d",), out.stdout) == "d"  # leading spaces count
    assert missing(("b  ",), out.stdout) == "b  "  # whole lines, trailing spaces stripped
    assert missing(("...", "c", "..."), out.stdout) is None  # "..." marks lines left out
    assert missing(("c", "...", "a"), out.stdout) == "a"  # and is no wildcard for order
    # every line left out is marked: b between a and c, everything before c, after a
    unmarked = "output lines the page leaves out without a '...' line:\n"
    assert missing(("a", "c", "  d"), out.stdout) == unmarked + "  b"
    assert missing(("c", "  d"), out.stdout) == unmarked + "  a\n  b"
    assert missing(("a", "..."), out.stdout) is None
    assert missing(("a",), out.stdout) == unmarked + "  b\n  c\n    d"
    assert missing(("a", "...", "b", "c", "  d"), out.stdout) is None  # "...": any number
    assert run(second, tmp_path).stdout == "one\n"  # the first block's file


def test_a_failing_command_fails_the_block(tmp_path: Path) -> None:
    """``-e`` and ``pipefail``: a failure in a pipe or mid-block is not hidden."""
    for script in ("false | cat\necho after\n", "false\necho after\n", "echo $UNSET\n"):
        out = run(Step(script, 1, ()), tmp_path)
        assert out.returncode != 0, script
        assert "after" not in out.stdout


def test_a_block_over_its_time_limit_is_killed_with_its_background_processes(
    tmp_path: Path,
) -> None:
    out = run(Step("sleep 30 &\nsleep 30\n", 1, ()), tmp_path, limit=1.0)
    assert out.returncode != 0
    assert "timed out" in out.stderr
