"""Recordings of a run: its trace as an MCAP file that Foxglove opens (issue 37).

:mod:`cfgplan.record.mcap_export` turns the JSON lines of ``cfgplan run
--trace FILE`` (:mod:`cfgplan.runtime.schema`) into MCAP, one channel per kind
of event; ``cfgplan record`` is its command. It needs the ``mcap`` package
(``pip install 'cfgplan[record]'``), so nothing here is imported by the
runtime, and importing this package loads nothing.
"""
