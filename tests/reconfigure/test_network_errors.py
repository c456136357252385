"""A helper's failing implementation is explained on the coordinator's console
(5.5): before, the coordinator said only that its input from the
helper went stale ("(stale)"), while the helper's own terminal had the error
with its file and line. Hermetic: loopback, free ports, scouting off, bounded
waits, every process stopped by its pid (:mod:`tests.runtime.netutil`)."""

from __future__ import annotations

import re
import textwrap
from pathlib import Path

import pytest

from tests.backends.support import EXAMPLE_IMPL
from tests.reconfigure.test_network import LIMIT, _network, _robot
from tests.runtime.netutil import processes


@pytest.mark.slow
def test_the_coordinator_says_what_a_helpers_implementation_raised(tmp_path: Path) -> None:
    broken = tmp_path / "broken.py"
    broken.write_text(
        textwrap.dedent(
            f"""
            from dataclasses import replace
            from pathlib import Path
            from cfgplan.runtime import Implementation, load_module
            _base = load_module(Path({str(EXAMPLE_IMPL)!r}))

            def transform_info(*args):
                return 1 / 0

            globals().update(
                {{k: replace(v, function=transform_info) if v.name == "transform-info" else v
                  for k, v in vars(_base).items() if isinstance(v, Implementation)}}
            )
            """
        )
    )
    emil_net, pippi_net = _network(tmp_path, "errors-test")
    with processes() as running:
        emil, _ = _robot(running, tmp_path, "Emil", EXAMPLE_IMPL, emil_net, "--cycles", "60")
        _robot(running, tmp_path, "Pippi", broken, pippi_net)
        assert emil.wait(LIMIT) is not None  # type: ignore[attr-defined]
        running.stop_all()
    log = (tmp_path / "emil.log").read_text()
    said = re.findall(r"Emil: Pippi (F\d+): transform-info\(Pippi, Emil, Door1\): (.*)", log)
    assert len(said) == 1, log  # once for the run of failed calls
    assert said[0][1].startswith("the implementation raised ZeroDivisionError: division by zero")
    assert "broken.py:" in said[0][1]  # where, as the helper's own terminal says it
