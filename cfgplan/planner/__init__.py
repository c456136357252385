"""The configuration planner of thesis 4.5.

The pipeline reads off the module names: ``task`` (the domain and state
compiled), ``unify`` and ``match`` (preconditions against the state),
``ground`` (instances made on demand), ``partial`` (the node and the two
steps that grow it), ``successors`` (one step of 4.5), ``bound`` (the
heuristic), ``search`` (best-first), ``dive`` (an anytime answer), ``finish``
(step 4: admissibility), ``report`` and ``explain`` (why nothing was found),
and ``plan``, the entry point.
"""

from cfgplan.planner.plan import plan
from cfgplan.planner.search import BestFirst, Stats

__all__ = ["BestFirst", "Stats", "plan"]
