"""The configuration planner of thesis 4.5.

The pipeline reads off the module names: ``task`` (the domain and state
compiled), ``unify`` and ``match`` (preconditions against the state),
``ground`` (instances made on demand), ``partial`` (the node and the two
steps that grow it), ``successors`` (one step of 4.5), ``bound`` and
``partition`` (the heuristics), ``pricer`` (a node's priority by them, and
when the dearer one is worth it), ``grow`` (what every strategy does to a
node), ``search`` (best-first), ``components`` and ``combine`` (a goal's
independent parts, searched apart and combined) and ``enumerate`` (every
configuration, in bounded memory), ``dive`` (an anytime answer), ``clock`` (the time limit),
``finish`` (step 4: admissibility), ``report`` and ``explain`` (why nothing
was found), and ``plan``, the entry point.
"""

from cfgplan.planner.plan import Run, plan
from cfgplan.planner.report import Stats

__all__ = ["Run", "Stats", "plan"]
