"""A small 2-D simulator to see configurations work (chapter 6, beyond the thesis).

The thesis ran cross-a-door and carry-a-bar on two Magellan Pro robots and
build-a-wall only in the planner. ``cfgplan simulate`` plans a scenario's
configuration (or sequence of them), runs it on :mod:`cfgplan.runtime` with
monitoring and reconfiguration (:mod:`cfgplan.reconfigure`), in simulated
time, against a world of rooms, doors, robots, a bar and blocks; and draws
what happened (Figs. 6.5 and 6.6). One module a part:

* ``scenario``, ``reading``, ``locate`` — scenario files, read and checked with positions;
* ``geometry``, ``bodies``, ``blocks``, ``sensors``, ``world`` — the world;
* ``onboard`` — what implementations may touch: their own robot's sensors
  and motors (:func:`hardware`), never the true state;
* ``perception`` — shared helpers of the bundled implementations (scan
  features, localization); ``impl`` — implementations of every
  functionality of the three bundled domains;
* ``run`` — the simulation loop; ``record`` — the trace and what ran when;
  ``report`` — summary and failures; ``outputs`` — what goes in ``--out``;
* ``drawing``, ``timeline``, ``trajectories``, ``laserview``, ``barplot``,
  ``animate``, ``diagrams`` — the pictures, and ``story``, what the timeline
  and diagrams draw (``cfgplan report`` draws a trace's with the same modules).

Needs the ``sim`` extra (numpy, shapely, matplotlib): ``pip install
'cfgplan[sim]'``. Importing this package imports nothing heavy:
implementations write ``from cfgplan.sim import hardware``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from cfgplan.sim.onboard import Hardware

__all__ = ["hardware"]


def hardware(robot: str | None = None) -> Hardware:
    """The running robot's sensors and motors (:mod:`cfgplan.sim.onboard`)."""
    from cfgplan.sim.onboard import hardware as get

    return get(robot)
