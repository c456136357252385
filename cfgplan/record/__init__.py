"""Recordings of a run, and the run served to Foxglove live.

* :mod:`~cfgplan.record.channels` — the one definition of the topics, JSON
  Schemas and message times that every writer below uses;
* :mod:`~cfgplan.record.mcap_export` — ``cfgplan record``: the JSON lines of
  ``cfgplan run --trace FILE`` (:mod:`cfgplan.runtime.schema`) as MCAP,
  afterwards;
* :mod:`~cfgplan.record.policy` and :mod:`~cfgplan.record.live` —
  ``--record FILE.mcap`` on ``run`` and ``simulate``: MCAP as the run goes,
  bounded;
* :mod:`~cfgplan.record.foxglove_live` — ``--foxglove [HOST:]PORT``: the
  foxglove-sdk WebSocket server with the same channels and the running
  configuration as its connection graph;
* :mod:`~cfgplan.record.launch` — starting those two beside a run.

They need the ``mcap`` package (``pip install 'cfgplan[record]'``) or
``foxglove-sdk`` (``pip install 'cfgplan[foxglove]'``), so nothing here is
imported by the runtime, and importing this package loads nothing.
"""
