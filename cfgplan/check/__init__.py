"""Static checks of domains, states and goals before planning (thesis 3.2-3.5, 4.4)."""

from cfgplan.check.checker import check

__all__ = ["check"]
