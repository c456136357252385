"""Implementations of every functionality of the three bundled domains, acting
in the simulator (:mod:`cfgplan.sim.onboard`): ``cross_door`` (Appendix
A.1, also ``domain-steps.lisp``), ``carry_bar`` (A.2), ``build_wall`` (A.3).

Sensing functionalities read their robot's sensors; computations use only
their inputs (and what the robot knows in advance: its map, the sizes of
blocks); actions drive their robot's motors with the data the
configuration's channels bring them. So any configuration the planner finds
for these domains runs, not only the cheapest. Give a scenario
``impl = "cfgplan.sim.impl.cross_door"`` (or a ``.py`` file of your own).
"""
