"""Pippi's part of a configuration, as Python (thesis 5.3; cfgplan emit).

Configuration rank 1, cost 44, for do-cross-door(Pippi, Door1).
The individual configuration (5.4):

    (configuration Pippi
      Functionalities:
        F10: compass(Pippi)
        F3: cross-door(Pippi, Door1)
      Channels:
        global(Pippi, Emil, F10, F12, global-orient(Pippi))
        global(Emil, Pippi, F7, F3, pos(Pippi, Door1))
        global(Emil, Pippi, F7, F3, orient(Pippi, Door1))
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
    "6f90748058e57910", "domain.lisp with state-6.2.2-step1.lisp, goal do-cross-door(Pippi, Door1)"
)


def configure(robot: Robot) -> Cycle:
    """Pippi's channels and functionalities; returns one cycle."""
    # LET: the channels CH-1 .. CH-3 (5.2.2, 5.3)
    ch_1 = robot.global_channel("Emil", "F10", "F12", ("global-orient", "Pippi"))
    ch_2 = robot.global_channel("Emil", "F7", "F3", ("pos", "Pippi", "Door1"))
    ch_3 = robot.global_channel("Emil", "F7", "F3", ("orient", "Pippi", "Door1"))
    # the wrappers of the functionalities (5.2.1), in sorted order
    # F10: compass(Pippi): no input -> global-orient(Pippi)
    f10_compass = robot.wrapper("F10", "compass", inputs=0)
    # F3: cross-door(Pippi, Door1): pos(Pippi, Door1), orient(Pippi, Door1) -> no output
    f3_cross_door = robot.wrapper("F3", "cross-door", ("Door1",), inputs=2)

    def cycle() -> None:
        """LAMBDA: each functionality once, in sorted order."""
        f10_compass(inputs=[], outputs=[[ch_1]])
        f3_cross_door(inputs=[ch_2, ch_3], outputs=[])

    return cycle


if __name__ == "__main__":
    raise SystemExit(robot_main(ROBOT, configure, problem=PROBLEM))
