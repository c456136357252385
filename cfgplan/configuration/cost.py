"""The cost of a configuration (thesis 3.5): ``10·robots + 3·global + local +
functionalities``, with settable weights and per-functionality ``:cost``.

Beyond the thesis, an agent the state declares ``(device X)`` (a ceiling
camera, a door with a sensor) is weighted by ``device`` instead of ``robot``;
both default to 10, so the thesis's numbers do not change."""

from __future__ import annotations

from pydantic import BaseModel, ConfigDict

from cfgplan.diagnostics import error


class Weights(BaseModel):
    """The weights of the cost sum; the thesis's are the defaults."""

    model_config = ConfigDict(frozen=True)

    robot: float = 10
    global_: float = 3
    local: float = 1
    functionality: float = 1
    device: float = 10

    def __str__(self) -> str:
        return (
            f"robot={fmt(self.robot)},global={fmt(self.global_)},"
            f"local={fmt(self.local)},functionality={fmt(self.functionality)},"
            f"device={fmt(self.device)}"
        )


_NAMES = {
    "robot": "robot",
    "global": "global_",
    "local": "local",
    "functionality": "functionality",
    "device": "device",
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
        if number < 0:
            raise error(f"bad weight {part!r}: weights are not negative")
        values[_NAMES[key]] = number
    return Weights(**values)


def fmt(number: float) -> str:
    """A number as the thesis prints it: 44, not 44.0."""
    return str(int(number)) if float(number).is_integer() else repr(float(number))
