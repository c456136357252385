"""The cost of a configuration (thesis 3.5): ``10·robots + 3·global + local +
functionalities``, with settable weights and per-functionality ``:cost``.

Beyond the thesis, an agent the state declares ``(device X)`` (a ceiling
camera, a door with a sensor) is weighted by ``device`` instead of ``robot``;
both default to 10, so the thesis's numbers do not change. And reliability
(7.2): a configuration's reliability is the product of its functionalities'
``:reliability`` and of the media its global channels may use (the most
reliable one between their robots); ``reliability=W`` adds ``W·(−ln
reliability)`` to the cost (0 by default), that is ``W·(−ln p)`` for each part."""

# No ``from __future__ import annotations``: pydantic takes the models' annotations
# as objects, with no string to evaluate for each field (start-up, docs/development.md).
import math

from pydantic import BaseModel, ConfigDict

from cfgplan.diagnostics import error
from cfgplan.ir.model import MAX_WEIGHT, Weight
from cfgplan.option_values import kept, rounding


class Weights(BaseModel):
    """The weights of the cost sum; the thesis's are the defaults."""

    model_config = ConfigDict(frozen=True)

    robot: Weight = 10
    global_: Weight = 3
    local: Weight = 1
    functionality: Weight = 1
    device: Weight = 10
    reliability: Weight = 0

    def __str__(self) -> str:
        return (
            f"robot={fmt(self.robot)},global={fmt(self.global_)},"
            f"local={fmt(self.local)},functionality={fmt(self.functionality)},"
            f"device={fmt(self.device)}"
            + (f",reliability={fmt(self.reliability)}" if self.reliability else "")
        )


_NAMES = {
    "robot": "robot",
    "global": "global_",
    "local": "local",
    "functionality": "functionality",
    "device": "device",
    "reliability": "reliability",
}


def parse_weights(text: str) -> Weights:
    """Read ``robot=10,global=3,local=1,functionality=1,device=10`` (any subset, any order)."""
    values: dict[str, float] = {}
    for part in filter(None, (p.strip() for p in text.split(","))):
        key, sep, value = part.partition("=")
        key = key.strip()
        if not sep or key not in _NAMES:
            raise error(
                f"bad weight {part!r}: expected NAME=NUMBER with NAME one of " + ", ".join(_NAMES)
            )
        try:
            number = float(value)
        except ValueError:
            raise error(f"bad weight {part!r}: {value.strip()!r} is not a number") from None
        if not math.isfinite(number) or number > MAX_WEIGHT:
            raise error(
                f"bad weight {part!r}: a weight is a finite number of at most {MAX_WEIGHT:g}"
            )
        if number < 0:
            raise error(f"bad weight {part!r}: weights are not negative")
        if not kept(value.strip(), number):
            raise error(f"bad weight {part!r}: {rounding(value.strip(), number)}")
        values[_NAMES[key]] = number
    return Weights(**values)


def fmt(number: float) -> str:
    """A number as the thesis prints it: 44, not 44.0 (at most 4 decimals:
    a reliability term makes costs such as 44.1054)."""
    rounded = round(float(number), 4)
    return str(int(rounded)) if rounded.is_integer() else repr(rounded)
