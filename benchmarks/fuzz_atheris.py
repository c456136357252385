"""Coverage-guided fuzzing of the reader, the checker and the diagnostics.

Optional: needs ``pip install atheris`` (wheels for Linux x86_64; not part of
the test extra). libFuzzer mutates the bundled domain and state files, guided
by the coverage of cfgplan's code, and every input is read as a domain and as
a state, checked against a bundled domain, and any error rendered as the
command line would. Anything but a :class:`CfgplanError` is a finding, which
libFuzzer saves as ``crash-*``. Run, for 15 minutes::

    python -m benchmarks.fuzz_atheris -max_total_time=900 -timeout=5 -rss_limit_mb=2048 \\
        CORPUS_DIR domains/*/

(``CORPUS_DIR`` an empty folder that collects the inputs that found new code.)
"""

from __future__ import annotations

import functools
import importlib
import sys
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]


@functools.cache
def _domain() -> Any:
    from cfgplan.syntax.reader import read_domain

    return read_domain(ROOT / "domains" / "cross-door" / "domain.lisp")[0]


def _one(data: bytes) -> None:
    from cfgplan.check import check
    from cfgplan.diagnostics import CfgplanError, render_all
    from cfgplan.syntax.reader import decode, domain_from, parse, state_from

    domain = _domain()
    try:
        text = decode(data, "fuzz.lisp")
        source = parse(text, "fuzz.lisp")
        if source.states or source.goals:
            state = state_from(source)
            check(domain, state, state.goal)
        else:
            check(domain_from(source))
    except CfgplanError as exc:
        render_all(exc.diagnostics, {"fuzz.lisp": data.decode("utf-8", "replace")})


def main() -> None:
    try:
        atheris: Any = importlib.import_module("atheris")
    except ImportError:
        sys.exit("benchmarks.fuzz_atheris needs atheris: pip install atheris (Linux x86_64)")
    with atheris.instrument_imports(include=["cfgplan"]):
        import cfgplan.check
        import cfgplan.syntax.reader  # noqa: F401
    atheris.Setup(sys.argv, _one)
    atheris.Fuzz()


if __name__ == "__main__":
    main()
