"""A live page of a running society: ``cfgplan run ... --live [HOST:]PORT`` (5.5).

The page shows the running configuration as its Graphviz drawing
(:mod:`cfgplan.backends.dot`) with each channel coloured by freshness, each
robot by liveliness and failed resources marked; a timeline of switches,
failures and recoveries with their causes; and the candidate fallbacks with
their costs (:mod:`cfgplan.reconfigure.fallbacks`). The server pushes it as
it changes (server-sent events).

* :mod:`~cfgplan.live.address` — ``[HOST:]PORT`` as the command line gives it;
* :mod:`~cfgplan.live.model` — the page's model, a pure function of the events;
* :mod:`~cfgplan.live.diagram` — the configuration's SVG, its parts tagged;
* :mod:`~cfgplan.live.watch` — what the robots' thread hands the server;
* :mod:`~cfgplan.live.server` — the aiohttp server, on a thread of its own;
* :mod:`~cfgplan.live.launch` — ``--live``: start it beside a run, stop it after.

Only :mod:`~cfgplan.live.server` imports aiohttp (the ``live`` extra), and
only when ``--live`` is given: the core install and a robot without
``--live`` never import it.
"""
