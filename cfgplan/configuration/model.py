"""Configurations as the planner returns them (thesis 3.5 and 4.4).

A configuration is ``<F, Ch>``: functionality instances with labels and
locations, and channels between them. Lists keep the thesis's order (the
newest functionality first; each method's channels ahead of older ones), which
the backends of chapter 5 rely on.
"""

# No ``from __future__ import annotations``: pydantic takes the models' annotations
# as objects, with no string to evaluate for each field (start-up, docs/development.md).
from typing import Literal

from pydantic import BaseModel, ConfigDict, Field

from cfgplan.configuration.cost import Weights
from cfgplan.notation import instance_text


class FunctionalityInstance(BaseModel):
    """``F113: transform-info(Emil, Pippi, Door1)``: runs on its first argument."""

    model_config = ConfigDict(frozen=True)

    label: str
    name: str
    args: tuple[str, ...]

    @property
    def robot(self) -> str:
        return self.args[0]

    @property
    def key(self) -> tuple[str, ...]:
        return (self.name, *self.args)

    def __str__(self) -> str:
        return instance_text(self.label, self.name, self.args)


class Channel(BaseModel):
    """A channel from one functionality's output to another's input (3.4)."""

    model_config = ConfigDict(frozen=True)

    kind: Literal["local", "global"]
    source: str
    target: str
    source_robot: str
    target_robot: str
    data: tuple[str, ...]
    bandwidth: float | None = None


class Assignment(BaseModel):
    """A global channel carried by a medium (communication admissibility, 4.6)."""

    model_config = ConfigDict(frozen=True)

    channel: int  # index into Configuration.channels
    medium: int  # index into State.media


class Configuration(BaseModel):
    """One admissible configuration with its cost and collected postconditions P."""

    model_config = ConfigDict(frozen=True)

    functionalities: tuple[FunctionalityInstance, ...]
    channels: tuple[Channel, ...]
    postconditions: tuple[str, ...] = ()
    cost: float
    weights: Weights = Weights()
    media: tuple[Assignment, ...] = ()
    derivation: int = 0  # which derivation (1-based, in thesis order) produced it
    proven: bool = True  # False: found by a dive after the search was stopped early
    devices: tuple[str, ...] = ()  # its agents the state declares (device X)
    reliability: float = 1.0  # the product of its parts' reliabilities (7.2)
    effects: tuple[tuple[bool, tuple[str, ...]], ...] = Field(default=(), exclude=True, repr=False)
    """P as data: (True, atom) adds the atom, (False, atom) deletes it; the
    printed form is :attr:`postconditions`."""

    @property
    def agents(self) -> list[str]:
        """Where its functionalities run (robots and devices), each once, in
        order of first appearance in the functionality list."""
        return list(dict.fromkeys(f.robot for f in self.functionalities))

    @property
    def robots(self) -> list[str]:
        """Its agents that are robots (not devices), in the order of :attr:`agents`."""
        return [a for a in self.agents if a not in self.devices]

    @property
    def global_channels(self) -> int:
        return sum(1 for c in self.channels if c.kind == "global")

    @property
    def local_channels(self) -> int:
        return sum(1 for c in self.channels if c.kind == "local")

    def functionality(self, label: str) -> FunctionalityInstance:
        for f in self.functionalities:
            if f.label == label:
                return f
        raise KeyError(label)

    def identity(
        self,
    ) -> tuple[frozenset[tuple[str, ...]], frozenset[tuple[object, ...]], frozenset[str]]:
        """What stays when labels are forgotten: equal identity, same configuration."""
        key = {f.label: f.key for f in self.functionalities}
        channels = frozenset(
            (c.kind, key[c.source], key[c.target], c.data, c.bandwidth) for c in self.channels
        )
        return frozenset(key.values()), channels, frozenset(self.postconditions)
