"""What goes wrong while running a configuration (chapter 5): :class:`RunError`,
defined in :mod:`cfgplan.run_errors` (below both the runtime and the security
package, which both raise it) and named here for the runtime's modules."""

from __future__ import annotations

from cfgplan.run_errors import RunError, location, printable

__all__ = ["RunError", "location", "printable"]
