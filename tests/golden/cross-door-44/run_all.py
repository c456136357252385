"""All robots of a configuration in one process (thesis 5.3; cfgplan emit).

Configuration rank 1, cost 44, for do-cross-door(Pippi, Door1): Pippi, Emil.
Each robot's module (pippi.py, emil.py) creates its channels and its cycle;
here their global channels are joined by an in-process transport and the
robots run one cycle each in turn. Run:

    python run_all.py --impl IMPL [--rate HZ] [--cycles N] [--duration S] [--trace FILE]
"""

from __future__ import annotations

from pathlib import Path

from cfgplan.runtime import Configure, load_module, society_main

HERE = Path(__file__).resolve().parent
ROBOTS = (
    ("Pippi", "pippi.py"),
    ("Emil", "emil.py"),
)


def programs() -> list[tuple[str, Configure]]:
    """Each robot and its configure function, from the modules beside this file."""
    return [(robot, load_module(HERE / file).configure) for robot, file in ROBOTS]


if __name__ == "__main__":
    raise SystemExit(society_main(programs()))
