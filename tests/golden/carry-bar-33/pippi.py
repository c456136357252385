"""Pippi's part of a configuration, as Python (thesis 5.3; cfgplan emit).

Configuration rank 1, cost 33, for do-carry-bar(Pippi).
The individual configuration (5.4):

    (configuration Pippi
      Functionalities:
        F5: lead-robot(Pippi, Emil)
      Channels:
        global(Emil, Pippi, F7, F5, dist(Emil, Pippi))
    )

configure() creates Pippi's channels (the LET of 5.3) and returns the cycle
(the LAMBDA): one call to each functionality, in sorted order (5.1). Run this
robot in a process of its own, its global channels over Zenoh (5.2.2):

    python pippi.py --impl IMPL [--listen ENDPOINT] [--connect ENDPOINT]
        [--society NAME] [--rate HZ] [--cycles N] [--duration S] [--trace FILE]

IMPL is a module name or a .py file declaring the implementations with
@functionality (cfgplan.runtime); --help lists every option. run_all.py runs
every robot of the configuration in one process.
"""

from __future__ import annotations

from cfgplan.runtime import Cycle, Robot, robot_main
from cfgplan.security.identity import ProblemId

ROBOT = "Pippi"
PROBLEM = ProblemId(
    "eeaa3426adda4de3", "domain.lisp with state-6.3.2.lisp, goal do-carry-bar(Pippi)"
)


def configure(robot: Robot) -> Cycle:
    """Pippi's channels and functionalities; returns one cycle."""
    # LET: the channels CH-1 .. CH-1 (5.2.2, 5.3)
    ch_1 = robot.global_channel("Emil", "F7", "F5", ("dist", "Emil", "Pippi"))
    # the wrappers of the functionalities (5.2.1), in sorted order
    # F5: lead-robot(Pippi, Emil): dist(Emil, Pippi) -> no output
    f5_lead_robot = robot.wrapper("F5", "lead-robot", ("Emil",), inputs=1)

    def cycle() -> None:
        """LAMBDA: each functionality once, in sorted order."""
        f5_lead_robot(inputs=[ch_1], outputs=[])

    return cycle


if __name__ == "__main__":
    raise SystemExit(robot_main(ROBOT, configure, problem=PROBLEM))
