"""Emil's part of a configuration, as Python (thesis 5.3; cfgplan emit).

Configuration rank 1, cost 33, for do-carry-bar(Pippi).
The individual configuration (5.4):

    (configuration Emil
      Functionalities:
        F6: laser(Emil)
        F7: meas-robot-angle-dist-laser(Emil, Pippi)
        F3: calc-robot-speed-diff(Emil, Pippi)
        F4: stalk-robot(Emil, Pippi)
      Channels:
        local(Emil, F6, F7, laser-reading(Emil))
        local(Emil, F7, F4, angle(Emil, Pippi))
        local(Emil, F7, F4, dist(Emil, Pippi))
        local(Emil, F7, F3, dist(Emil, Pippi))
        local(Emil, F3, F4, speed-diff(Emil, Pippi))
        global(Emil, Pippi, F7, F5, dist(Emil, Pippi))
    )

configure() creates Emil's channels (the LET of 5.3) and returns the cycle
(the LAMBDA): one call to each functionality, in sorted order (5.1). Run this
robot in a process of its own, its global channels over Zenoh (5.2.2):

    python emil.py --impl IMPL [--listen ENDPOINT] [--connect ENDPOINT]
        [--society NAME] [--rate HZ] [--cycles N] [--duration S] [--trace FILE]

IMPL is a module name or a .py file declaring the implementations with
@functionality (cfgplan.runtime); --help lists every option. run_all.py runs
every robot of the configuration in one process.
"""

from __future__ import annotations

from cfgplan.runtime import Cycle, Robot, robot_main
from cfgplan.security.identity import ProblemId

ROBOT = "Emil"
PROBLEM = ProblemId(
    "eeaa3426adda4de3", "domain.lisp with state-6.3.2.lisp, goal do-carry-bar(Pippi)"
)


def configure(robot: Robot) -> Cycle:
    """Emil's channels and functionalities; returns one cycle."""
    # LET: the channels CH-1 .. CH-6 (5.2.2, 5.3)
    ch_1 = robot.local_channel("F6", "F7", ("laser-reading", "Emil"))
    ch_2 = robot.local_channel("F7", "F4", ("angle", "Emil", "Pippi"))
    ch_3 = robot.local_channel("F7", "F4", ("dist", "Emil", "Pippi"))
    ch_4 = robot.local_channel("F7", "F3", ("dist", "Emil", "Pippi"))
    ch_5 = robot.local_channel("F3", "F4", ("speed-diff", "Emil", "Pippi"))
    ch_6 = robot.global_channel("Pippi", "F7", "F5", ("dist", "Emil", "Pippi"))
    # the wrappers of the functionalities (5.2.1), in sorted order
    # F6: laser(Emil): no input -> laser-reading(Emil)
    f6_laser = robot.wrapper("F6", "laser", inputs=0)
    # F7: meas-robot-angle-dist-laser(Emil, Pippi)
    #   in: laser-reading(Emil)
    #   out: angle(Emil, Pippi), dist(Emil, Pippi)
    f7_meas_robot_angle_dist_laser = robot.wrapper(
        "F7", "meas-robot-angle-dist-laser", ("Pippi",), inputs=1
    )
    # F3: calc-robot-speed-diff(Emil, Pippi): dist(Emil, Pippi) -> speed-diff(Emil, Pippi)
    f3_calc_robot_speed_diff = robot.wrapper("F3", "calc-robot-speed-diff", ("Pippi",), inputs=1)
    # F4: stalk-robot(Emil, Pippi)
    #   in: angle(Emil, Pippi), dist(Emil, Pippi), speed-diff(Emil, Pippi)
    #   out: no output
    f4_stalk_robot = robot.wrapper("F4", "stalk-robot", ("Pippi",), inputs=3)

    def cycle() -> None:
        """LAMBDA: each functionality once, in sorted order."""
        f6_laser(inputs=[], outputs=[[ch_1]])
        f7_meas_robot_angle_dist_laser(inputs=[ch_1], outputs=[[ch_2], [ch_3, ch_4, ch_6]])
        f3_calc_robot_speed_diff(inputs=[ch_4], outputs=[[ch_5]])
        f4_stalk_robot(inputs=[ch_2, ch_3, ch_5], outputs=[])

    return cycle


if __name__ == "__main__":
    raise SystemExit(robot_main(ROBOT, configure, problem=PROBLEM))
