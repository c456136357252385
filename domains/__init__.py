"""Package data: the thesis's domains, states and simulation scenarios
(installed as ``cfgplan.domains``, so that ``cfgplan simulate cross-door``
finds them outside a clone of the repository)."""
