"""The base of the pydantic models that describe cfgplan's JSON documents: the
output of ``cfgplan plan`` (:mod:`cfgplan.configuration.schema`) and the
trace of a run (:mod:`cfgplan.runtime.schema`), whose JSON Schemas the
documentation's reference pages are generated from. Neither is imported on
the command line's hot path or by a robot's program."""

from __future__ import annotations

from pydantic import BaseModel, ConfigDict

__all__ = ["Closed", "Number"]

Number = int | float
"""A cost, bandwidth or capacity: written ``44``, not ``44.0``, when whole."""


class Closed(BaseModel):
    """A JSON object whose keys are all named here (validation refuses others)."""

    model_config = ConfigDict(extra="forbid", frozen=True, strict=True, populate_by_name=True)
