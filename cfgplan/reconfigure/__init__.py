"""Monitoring and reconfiguration, the planning side (thesis 5.5, 7.2, 7.3).

What the thesis's operator did by hand in 6.2.2 step 3 and 6.3.2 — notice a
failure, update the state, re-plan, deploy the new configuration — done by
the system. One module a step:

* ``withdraw`` — which facts a failure takes away, read off the domain;
* ``situation`` — what has changed, and the task to re-plan with, derived
  from the compiled task without a cold start;
* ``fallbacks`` — the best configuration if each resource fails
  (``cfgplan plan --fallbacks``); ``ahead`` computes them on a thread;
* ``switch`` — relabelling and the kept/stopped/started split of a switch;
* ``policy`` — what to run after each change, with hysteresis;
* ``coordinate`` — detections in, switches out, trace events;
* ``local`` and ``network`` — deploying in one process, or across processes
  by the two-phase protocol; ``setup`` chooses for ``cfgplan run``.

The robots' side (detection, probes, fault injection, installing a part, the
protocol's member) is in :mod:`cfgplan.runtime`, which needs no planner.
"""
