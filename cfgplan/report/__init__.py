"""Reports of any run: ``cfgplan report RUN [-o DIR]``.

RUN is an MCAP recording or JSON-lines traces, of ``cfgplan run`` or
``cfgplan simulate``. One module a part:

* ``story`` — what the pictures show (robots, steps, configurations over
  time, switches, failures and recoveries), from a trace's events;
* ``source`` — reading RUN: trace files or an MCAP recording (through the
  ``mcap`` package's reader), and a simulation's ``summary.json`` beside it;
* ``replay`` — a simulation's poses, by running it again from its seed and
  checking that it gives the same trace;
* ``page`` — the self-contained ``report.html`` (inline SVG);
* ``make`` — the whole report, picture by picture.

The pictures are drawn by the simulator's modules (:mod:`cfgplan.sim.timeline`,
:mod:`cfgplan.sim.diagrams`, :mod:`cfgplan.sim.trajectories`,
:mod:`cfgplan.sim.barplot`): one drawing module per picture, used by both.
Needs matplotlib (the ``sim`` extra), and ``mcap`` for recordings (``record``).
"""
