"""cfgplan: plan-based configuration of robot societies.

The pipeline follows R. Lundh, *Plan-Based Configuration of a Group of Robots*
(2006): ``syntax`` reads domains and states into the ``ir``; ``check`` validates
them; ``planner`` expands a goal into ranked admissible configurations
(``configuration``); ``backends`` sort, divide and emit per-robot code and
diagrams; ``runtime`` runs them.

Importing this package imports nothing else: ``cfgplan --version`` and every
robot program start here.
"""

__version__ = "0.1.0"
"""The one place of the version: the package metadata is built from it
(pyproject.toml's ``dynamic``), and ``cfgplan --version`` prints it."""
