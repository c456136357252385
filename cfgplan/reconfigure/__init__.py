"""Monitoring and reconfiguration, the planner's side (thesis 5.5, 7.2, 7.3).

What the thesis's operator did by hand in 6.2.2 step 3 and 6.3.2 — notice a
failure, update the state, re-plan, deploy the new configuration — done by
the system: ``withdraw`` (which facts a failure takes away, from the domain),
``situation`` (what changed; the task to re-plan with, derived without a
cold start), ``fallbacks`` (the best configuration if each resource fails),
``switch`` (the least disruptive way from one configuration to another),
``policy`` (when to switch: hysteresis), and the drivers that run it on a
society in one process (``local``) or across processes (``coordinator``).
The robots' side (detection, installing parts, the protocol's member) is in
:mod:`cfgplan.runtime`, which needs no planner.
"""
