"""Emil's part of a configuration, as Python (thesis 5.3; cfgplan emit).

Configuration rank 1, cost 44, for do-cross-door(Pippi, Door1).
The individual configuration (5.4):

    (configuration Emil
      Functionalities:
        F11: compass(Emil)
        F8: camera(Emil)
        F14: measure-robot-pos(Emil, Pippi)
        F12: measure-robot-orient-compass(Emil, Pippi)
        F9: measure-door(Emil, Door1)
        F7: transform-info(Emil, Pippi, Door1)
      Channels:
        local(Emil, F8, F14, image(Emil))
        global(Pippi, Emil, F10, F12, global-orient(Pippi))
        local(Emil, F11, F12, global-orient(Emil))
        local(Emil, F8, F9, image(Emil))
        local(Emil, F9, F7, pos(Emil, Door1))
        local(Emil, F9, F7, orient(Emil, Door1))
        local(Emil, F12, F7, orient(Emil, Pippi))
        local(Emil, F14, F7, pos(Emil, Pippi))
        global(Emil, Pippi, F7, F3, pos(Pippi, Door1))
        global(Emil, Pippi, F7, F3, orient(Pippi, Door1))
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
    "6f90748058e57910", "domain.lisp with state-6.2.2-step1.lisp, goal do-cross-door(Pippi, Door1)"
)


def configure(robot: Robot) -> Cycle:
    """Emil's channels and functionalities; returns one cycle."""
    # LET: the channels CH-1 .. CH-10 (5.2.2, 5.3)
    ch_1 = robot.local_channel("F8", "F14", ("image", "Emil"))
    ch_2 = robot.global_channel("Pippi", "F10", "F12", ("global-orient", "Pippi"))
    ch_3 = robot.local_channel("F11", "F12", ("global-orient", "Emil"))
    ch_4 = robot.local_channel("F8", "F9", ("image", "Emil"))
    ch_5 = robot.local_channel("F9", "F7", ("pos", "Emil", "Door1"))
    ch_6 = robot.local_channel("F9", "F7", ("orient", "Emil", "Door1"))
    ch_7 = robot.local_channel("F12", "F7", ("orient", "Emil", "Pippi"))
    ch_8 = robot.local_channel("F14", "F7", ("pos", "Emil", "Pippi"))
    ch_9 = robot.global_channel("Pippi", "F7", "F3", ("pos", "Pippi", "Door1"))
    ch_10 = robot.global_channel("Pippi", "F7", "F3", ("orient", "Pippi", "Door1"))
    # the wrappers of the functionalities (5.2.1), in sorted order
    # F11: compass(Emil): no input -> global-orient(Emil)
    f11_compass = robot.wrapper("F11", "compass", inputs=0)
    # F8: camera(Emil): no input -> image(Emil)
    f8_camera = robot.wrapper("F8", "camera", inputs=0)
    # F14: measure-robot-pos(Emil, Pippi): image(Emil) -> pos(Emil, Pippi)
    f14_measure_robot_pos = robot.wrapper("F14", "measure-robot-pos", ("Pippi",), inputs=1)
    # F12: measure-robot-orient-compass(Emil, Pippi)
    #   in: global-orient(Emil), global-orient(Pippi)
    #   out: orient(Emil, Pippi)
    f12_measure_robot_orient_compass = robot.wrapper(
        "F12", "measure-robot-orient-compass", ("Pippi",), inputs=2
    )
    # F9: measure-door(Emil, Door1): image(Emil) -> pos(Emil, Door1), orient(Emil, Door1)
    f9_measure_door = robot.wrapper("F9", "measure-door", ("Door1",), inputs=1)
    # F7: transform-info(Emil, Pippi, Door1)
    #   in: orient(Emil, Pippi), pos(Emil, Pippi), orient(Emil, Door1), pos(Emil, Door1)
    #   out: orient(Pippi, Door1), pos(Pippi, Door1)
    f7_transform_info = robot.wrapper("F7", "transform-info", ("Pippi", "Door1"), inputs=4)

    def cycle() -> None:
        """LAMBDA: each functionality once, in sorted order."""
        f11_compass(inputs=[], outputs=[[ch_3]])
        f8_camera(inputs=[], outputs=[[ch_1, ch_4]])
        f14_measure_robot_pos(inputs=[ch_1], outputs=[[ch_8]])
        f12_measure_robot_orient_compass(inputs=[ch_3, ch_2], outputs=[[ch_7]])
        f9_measure_door(inputs=[ch_4], outputs=[[ch_5], [ch_6]])
        f7_transform_info(inputs=[ch_7, ch_8, ch_6, ch_5], outputs=[[ch_10], [ch_9]])

    return cycle


if __name__ == "__main__":
    raise SystemExit(robot_main(ROBOT, configure, problem=PROBLEM))
